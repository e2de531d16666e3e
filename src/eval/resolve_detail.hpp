#pragma once
// private to the eval layer: helpers shared by name resolution (resolve.cpp) and the episode
// function (episode_fn.cpp)

#include "actionshift/core/manifest.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace actionshift::eval::detail {

// the built-in manifest or manifest file `name`, refused (InputError) if it is a pool and `pool` is
// false or the other way round
Manifest manifest_of_kind(const std::string& name, bool pool);

// a method's parameters as a JSON object (InputError naming the method otherwise)
nlohmann::json parse_params(const std::string& text, const std::string& method);

}  // namespace actionshift::eval::detail
