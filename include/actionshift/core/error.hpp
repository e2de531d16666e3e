#pragma once
/// \file Error types and boundary checks shared by every layer.

#include <stdexcept>
#include <string>
#include <utility>

namespace actionshift {

/// Bad input at a boundary (a file, a field, a command-line value).
/// `what()` is one line: `<source>: <field>: <reason>`; empty parts are left out.
class InputError : public std::invalid_argument {
 public:
  InputError(std::string source, std::string field, std::string reason)
      : std::invalid_argument(compose(source, field, reason)),
        source_(std::move(source)),
        field_(std::move(field)),
        reason_(std::move(reason)) {}

  const std::string& source() const noexcept { return source_; }  ///< file or stream name
  const std::string& field() const noexcept { return field_; }    ///< field path, e.g. `test[3].contract.scale`
  const std::string& reason() const noexcept { return reason_; }  ///< what is wrong

 private:
  static std::string compose(const std::string& s, const std::string& f, const std::string& r) {
    std::string out;
    for (const std::string* part : {&s, &f}) {
      if (!part->empty()) out += *part + ": ";
    }
    out += r;
    return out;
  }
  std::string source_, field_, reason_;
};

}  // namespace actionshift

/// A boundary check that is never compiled out (unlike assert): throws std::invalid_argument.
#define ACTIONSHIFT_CHECK(cond, message)                      \
  do {                                                        \
    if (!(cond)) throw std::invalid_argument(std::string(message)); \
  } while (false)
