#include "actionshift/data/paper_numbers.hpp"

namespace actionshift::embedded {
extern const std::string_view paper_numbers;  // configs/paper/numbers.json
}

namespace actionshift::data {

std::string_view builtin_paper_numbers_text() { return embedded::paper_numbers; }

}  // namespace actionshift::data
