#include "actionshift/core/canonical_json.hpp"
#include "actionshift/core/hash.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace actionshift {
namespace {

TEST(PythonFloatRepr, MatchesPythonForGridValues) {
  EXPECT_EQ(python_float_repr(1.0), "1.0");
  EXPECT_EQ(python_float_repr(0.5), "0.5");
  EXPECT_EQ(python_float_repr(0.6), "0.6");
  EXPECT_EQ(python_float_repr(0.75), "0.75");
  EXPECT_EQ(python_float_repr(1.25), "1.25");
  EXPECT_EQ(python_float_repr(2.0), "2.0");
  EXPECT_EQ(python_float_repr(-0.0), "-0.0");
  EXPECT_EQ(python_float_repr(0.0), "0.0");
}

TEST(PythonFloatRepr, SwitchesToExponentLikePython) {
  // values checked against CPython 3.11 repr()
  EXPECT_EQ(python_float_repr(1e-4), "0.0001");
  EXPECT_EQ(python_float_repr(1e-5), "1e-05");
  EXPECT_EQ(python_float_repr(1.5e-7), "1.5e-07");
  EXPECT_EQ(python_float_repr(1e15), "1000000000000000.0");
  EXPECT_EQ(python_float_repr(1e16), "1e+16");
  EXPECT_EQ(python_float_repr(1.2345e22), "1.2345e+22");
  EXPECT_EQ(python_float_repr(123.456), "123.456");
  EXPECT_EQ(python_float_repr(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(python_float_repr(-2.5e-300), "-2.5e-300");
  EXPECT_EQ(python_float_repr(1e100), "1e+100");
  EXPECT_EQ(python_float_repr(0.0666666666666667), "0.0666666666666667");
}

TEST(PythonFloatRepr, RejectsNonFinite) {
  EXPECT_THROW(python_float_repr(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_THROW(python_float_repr(std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST(CanonicalDump, SortedCompactAsciiLikePythonJsonDumps) {
  nlohmann::json j = {{"b", 1}, {"a", {1.0, 2, "x"}}, {"c", {{"z", true}, {"y", nullptr}}}, {"é", "ü"}};
  EXPECT_EQ(canonical_dump(j), R"({"a":[1.0,2,"x"],"b":1,"c":{"y":null,"z":true},"\u00e9":"\u00fc"})");
}

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // golden vector from the reference implementation (docs/reference.md, Contracts)
  EXPECT_EQ(sha256_hex("{\"success\":true}\n"), "b493cdb3b30ea63f6a924f814dfccfcfe305dac02106f9994ce2bcb2e8ed28c4");
  EXPECT_TRUE(is_sha256_hex(sha256_hex("")));
  EXPECT_FALSE(is_sha256_hex("ABC"));
}

}  // namespace
}  // namespace actionshift
