// A runtime file that includes the trainer: check_include_arrows.cmake must reject it.
#include "weft/fit/mlp.h"
