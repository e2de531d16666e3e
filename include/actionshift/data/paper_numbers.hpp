#pragma once
/// \file The paper's numbers (configs/paper/numbers.json), compiled into ActionShift::data so that
/// `actionshift compare` sets them beside results with no file next to the binary.

#include <string_view>

namespace actionshift::data {

/// The exact text of the committed configs/paper/numbers.json (format: docs/formats.md "Paper numbers";
/// parsed by eval::parse_paper_numbers).
std::string_view builtin_paper_numbers_text();

}  // namespace actionshift::data
