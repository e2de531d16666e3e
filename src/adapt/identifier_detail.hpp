#pragma once
// private to the adapt layer: what the identifier weight-file reader and the weights cache share

#include <cstdint>

namespace actionshift::adapt::detail {

// largest identifier weight file read (a committed one is a few MB)
inline constexpr std::uintmax_t kMaxIdentifierFileBytes = std::uintmax_t{1} << 28;

}  // namespace actionshift::adapt::detail
