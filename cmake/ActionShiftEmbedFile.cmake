# script mode: turn IN into a C++ source defining actionshift::embedded::SYMBOL
file(READ "${IN}" hex HEX)
string(LENGTH "${hex}" n)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," bytes "${hex}")
math(EXPR len "${n} / 2")
file(WRITE "${OUT}" "// generated from ${IN}; do not edit\n#include <string_view>\nnamespace actionshift::embedded {\nstatic const char ${SYMBOL}_data[] = {${bytes} '\\0'};\nextern const std::string_view ${SYMBOL};\nconst std::string_view ${SYMBOL}(${SYMBOL}_data, ${len});\n}\n")
