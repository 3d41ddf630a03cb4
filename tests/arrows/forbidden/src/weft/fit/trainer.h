// The trainer may include the runtime.
#include "weft/yarn/network.h"
