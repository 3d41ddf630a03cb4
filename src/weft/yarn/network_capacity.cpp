// The renderer's network limits (network_capacity.h) and the check of a
// configured architecture against them.
#include "weft/yarn/network_capacity.h"

#include "weft/core/error.h"

namespace weft {

namespace {

// Where the limits are defined, for messages.
constexpr const char* kCapacitySource = "src/weft/yarn/network_capacity.h";

std::string listText(const std::vector<int>& values) {
    std::string text = "[";
    for (size_t k = 0; k < values.size(); ++k) {
        if (k > 0) text += ", ";
        text += std::to_string(values[k]);
    }
    text += ']';
    return text;
}

// "6-64-64-3": the network's widths, inputs and outputs included.
std::string architectureText(const std::vector<int>& hidden, const NetworkCapacity& capacity) {
    std::string text = std::to_string(capacity.inputs);
    for (int width : hidden) {
        text += '-';
        text += std::to_string(width);
    }
    text += '-';
    text += std::to_string(capacity.outputs);
    return text;
}

}  // namespace

long long paddedParameterCount(const std::vector<int>& hidden, const NetworkCapacity& capacity) {
    long long floats = 0;
    int in = capacity.inputs;
    for (int width : hidden) {
        floats += paddedLayerFloats(in, width, true);
        in = width;
    }
    return floats + paddedLayerFloats(in, capacity.outputs, false);
}

void checkHiddenWidths(const std::vector<int>& hidden, const NetworkCapacity& capacity,
                       const std::string& field) {
    const std::string network = std::string("the renderer's ") + capacity.name + " network";
    const auto refuse = [&](const std::string& why) {
        throw InputError(field + " = " + listText(hidden) + " is out of range: " + why + " (" +
                         kCapacitySource + ")");
    };
    for (int width : hidden)
        if (width < 1) refuse("a layer is at least 1 wide");
    for (int width : hidden)
        if (width > capacity.maxWidth)
            refuse(network + " holds layers at most " + std::to_string(capacity.maxWidth) +
                   " wide");
    if (hidden.size() + 1 > static_cast<size_t>(capacity.maxLayers))
        refuse(network + " holds at most " + std::to_string(capacity.maxLayers - 1) +
               " hidden layers");
    const long long floats = paddedParameterCount(hidden, capacity);
    if (floats > capacity.floats)
        refuse(network + " holds " + std::to_string(capacity.floats) +
               " parameters, each layer's outputs padded to a multiple of " +
               std::to_string(kNetworkPaddingLanes) + ", and " +
               architectureText(hidden, capacity) + " needs " + std::to_string(floats));
}

}  // namespace weft
