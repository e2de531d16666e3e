#include "actionshift/core/contract.hpp"
#include "actionshift/core/json_input.hpp"
#include "actionshift/core/reference_contracts.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace actionshift {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(Contract, IdentityCanonicalJsonAndHashMatchReference) {
  const Contract id = Contract::identity();
  EXPECT_EQ(id.to_json(),
            R"({"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"delta"})");
  EXPECT_EQ(id.sha256(), "6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa");
  EXPECT_TRUE(id.composition_signature().empty());
}

// quoting input into a message (core/error.hpp): one line, valid UTF-8, bounded length
TEST(InputText, PrintableInputEscapesControlBytesAndInvalidUtf8AndCuts) {
  EXPECT_EQ(printable_input("plain name"), "plain name");
  EXPECT_EQ(printable_input("a\nb\tc\rd"), "a\\nb\\tc\\rd");
  EXPECT_EQ(printable_input(std::string("x\0y\x7f", 4)), "x\\x00y\\x7f");
  EXPECT_EQ(printable_input("caf\xc3\xa9"), "caf\xc3\xa9") << "well-formed UTF-8 is kept";
  EXPECT_EQ(printable_input("\xff\xc3"), "\\xff\\xc3") << "a stray byte and a truncated sequence are escaped";
  EXPECT_EQ(printable_input("\xed\xa0\x80"), "\\xed\\xa0\\x80") << "an encoded surrogate is not UTF-8";
  EXPECT_EQ(printable_input(std::string(100, 'k'), 10), "kkkkkkkkkk... (90 more bytes)");
  EXPECT_EQ(quote_input("a\nb"), "'a\\nb'");
  EXPECT_EQ(quote_input("a", '"'), "\"a\"");
  EXPECT_EQ(invalid_utf8_offset("ok \xc3\xa9 \xe2\x82"), 6u);
  EXPECT_EQ(invalid_utf8_offset("ok \xf0\x9f\x98\x80"), std::string_view::npos);
  // every part of an InputError is made one line, whatever its caller passed
  const InputError e("a\nfile", "key\r\nx", "reason with\na newline and \xff");
  EXPECT_STREQ(e.what(), "a\\nfile: key\\r\\nx: reason with\\na newline and \\xff");
  // a JSON value in a message never throws on a string that is not UTF-8 (nlohmann's type_error 316)
  EXPECT_EQ(json_for_message(nlohmann::json("a\xff")), "\"a\xef\xbf\xbd\"");
  EXPECT_EQ(json_for_message(nlohmann::json(std::string(200, 'z')), 12), "\"zzzzzzzzzzz... (190 more bytes)");
}

TEST(Contract, UnknownKeysAreQuotedOnOneLine) {
  // a key with an escaped newline decodes to a newline; the message escapes it and cuts long keys
  const std::string text = R"({"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],)"
                           R"("scale":[1,1,1,1,1,1],"sign":[1,1,1,1,1,1],"target":"delta","x\ny":1,")" +
                           std::string(500, 'q') + R"(":2})";
  try {
    (void)Contract::from_json(text);
    FAIL() << "unknown keys accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_THAT(what, HasSubstr("unknown contract fields: "));
    EXPECT_THAT(what, HasSubstr("x\\ny"));
    EXPECT_LT(what.size(), 200u) << what;
  }
}

TEST(Contract, ReferenceGoldenHashes) {
  // golden hashes: docs/reference.md, Contracts
  const auto seen = reference::representative_contracts("seen");
  const auto unseen = reference::representative_contracts("unseen_composition");
  const auto lag = reference::representative_contracts("long_lag");
  EXPECT_EQ(seen[0].sha256(), "d1bb0bda71fc3b1aff5372b4c4d64823538015fe4d9be25252621523ccff41a6");
  EXPECT_EQ(seen[1].sha256(), "72c2eb7b5279ca9fee28c0978c2b05d5cdce24edd6e9fb87e3639782374a37c5");
  EXPECT_EQ(unseen[0].sha256(), "d0e2444c69e70093190cf78310ec67ad7a30af20a395380764d7a990b2634468");
  EXPECT_EQ(unseen[1].sha256(), "af0651087c490513825cb1253713dae5d4855a5fd115829e8353c2b16f00994e");
  EXPECT_EQ(lag[0].sha256(), "2f93a8433622284510b4a1d5f75bbdbb8945b8e9adbbc9c7e0ab9dc530363b97");
  EXPECT_EQ(lag[1].sha256(), "182965a71d658df1bd5e692429afa334ae708460550c2776a449c8dcbec23fa3");
  EXPECT_EQ(reference::distractor_a().sha256(), "44a1aa9652f9ac2788cfa02a54665f9ed62d588fe8ccf21a334cd3b67a4d28d7");
  EXPECT_EQ(reference::distractor_b().sha256(), "b904a76d3a73d6a91cd9da7b3cb8a3f74547fcc2c774a0cb26762aa10f73f3e7");
  EXPECT_EQ(pool_sha256(reference::pool9()), "b177b082925800655dee9e93c02142f26a703fd2bdf1d97be56a2cb0bf0eeea3");
}

TEST(Contract, SmokeContractHash) {
  ContractFields f;
  f.permutation = {1, 0, 2, 4, 3, 5};
  f.sign = {-1, 1, 1, -1, 1, 1};
  f.scale = {0.5, 1.5, 1.0, 1.0, 0.75, 1.25};
  f.gripper_inverted = true;
  EXPECT_EQ(Contract::make(f).sha256(), "1f5840ca50b1528bfd7d6c471f0c73dc15598e50e1e7cd5a98b10ec78e0e3a92");
}

TEST(Contract, CompositionSignatureOrderAndNames) {
  EXPECT_EQ(reference::representative_contracts("unseen_composition")[0].composition_signature(),
            (std::vector<std::string>{"permutation", "sign", "scale", "target", "frame", "gripper"}));
  EXPECT_EQ(reference::representative_contracts("long_lag")[0].composition_signature(),
            (std::vector<std::string>{"permutation", "sign", "scale", "lag", "gripper"}));
}

TEST(Contract, JsonRoundTrip) {
  for (const auto& c : reference::pool9()) {
    EXPECT_EQ(Contract::from_json(c.to_json()), c);
    EXPECT_EQ(Contract::from_json(c.to_json()).to_json(), c.to_json());
  }
}

TEST(Contract, FromJsonCoercesIntegerScalesToFloat) {
  const auto c = Contract::from_json(
      R"({"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1,1,1,1,1,1],"sign":[1,1,1,1,1,1],"target":"delta"})");
  EXPECT_EQ(c.sha256(), Contract::identity().sha256());
}

// every validation rule, with the reference's message (docs/reference.md, *Contracts*)
struct BadCase {
  const char* json;
  const char* message;
};

class ContractValidation : public ::testing::TestWithParam<BadCase> {};

TEST_P(ContractValidation, RejectsWithMessage) {
  EXPECT_THAT([] { Contract::from_json(std::string_view(GetParam().json)); },
              ThrowsMessage<std::invalid_argument>(HasSubstr(GetParam().message)));
}

#define BODY(perm, sign, scale, target, frame, lag, grip)                                                         \
  "{\"frame\":" frame ",\"gripper_inverted\":" grip ",\"lag\":" lag ",\"permutation\":" perm ",\"scale\":" scale \
  ",\"sign\":" sign ",\"target\":" target "}"
#define OK_PERM "[0,1,2,3,4,5]"
#define OK_SIGN "[1,1,1,1,1,1]"
#define OK_SCALE "[1.0,1.0,1.0,1.0,1.0,1.0]"

INSTANTIATE_TEST_SUITE_P(
    AllRules, ContractValidation,
    ::testing::Values(
        BadCase{"", "contract: not valid JSON"}, BadCase{"{", "contract: not valid JSON"},
        BadCase{"[1,2]", "contract must be a JSON object"},
        BadCase{BODY("[]", "[]", "[]", "\"delta\"", "\"base\"", "0", "false"), "contract must have at least one pose component"},
        BadCase{BODY(OK_PERM, "[1,1]", OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "contract component dimensions must match"},
        BadCase{BODY("[0,1]", "[1,1]", "[1.0,1.0]", "\"delta\"", "\"base\"", "0", "false"), "contract must have 6 pose components"},
        BadCase{BODY("[0,1,2,3,4,4]", OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "permutation must be a bijection over component indices"},
        BadCase{BODY("[0,1,2,3,4,6]", OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "permutation must be a bijection over component indices"},
        BadCase{BODY(OK_PERM, "[1,1,1,1,1,2]", OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "sign values must be -1 or 1"},
        BadCase{BODY(OK_PERM, "[1,1,1,1,1,0]", OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "sign values must be -1 or 1"},
        BadCase{BODY(OK_PERM, OK_SIGN, "[1.0,1.0,1.0,1.0,1.0,-0.5]", "\"delta\"", "\"base\"", "0", "false"), "scale values must be finite and positive"},
        BadCase{BODY(OK_PERM, OK_SIGN, "[1.0,1.0,1.0,1.0,1.0,0.0]", "\"delta\"", "\"base\"", "0", "false"), "scale values must be finite and positive"},
        BadCase{BODY(OK_PERM, OK_SIGN, "[1.0,1.0,1.0,1.0,1.0,NaN]", "\"delta\"", "\"base\"", "0", "false"), "contract: scale[]: not valid JSON"},
        BadCase{BODY(OK_PERM, OK_SIGN, "[1.0,1.0,1.0,1.0,1.0,1e999]", "\"delta\"", "\"base\"", "0", "false"), "contract: scale[]: number out of range"},
        BadCase{BODY(OK_PERM, OK_SIGN, "[1.0,1.0,1.0,1.0,1.0,\"1\"]", "\"delta\"", "\"base\"", "0", "false"), "scale must be a list of numbers"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "1.5", "false"), "lag must be an integer"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "true", "false"), "lag must be an integer"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "-1", "false"), "lag must be nonnegative"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "5000", "false"), "lag must be at most 1024"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"relative\"", "\"base\"", "0", "false"), "target must be 'delta' or 'absolute'"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"world\"", "0", "false"), "frame must be 'base' or 'tool'"},
        BadCase{BODY(OK_PERM, OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "0", "1"), "gripper_inverted must be boolean"},
        BadCase{BODY("[0,1,2,3,4,5.0]", OK_SIGN, OK_SCALE, "\"delta\"", "\"base\"", "0", "false"), "permutation must be a list of integers"},
        BadCase{R"({"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"delta","zeta":1,"alpha":2})",
                "unknown contract fields: alpha, zeta"},
        BadCase{R"({"frame":"base","permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1]})",
                "missing contract fields: gripper_inverted, lag, target"},
        // a repeated key: JSON parsers keep one of the two values silently (nlohmann the last)
        BadCase{R"({"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"delta","lag":3})",
                "contract: lag: duplicate key in one object"}));

TEST(JsonInput, RepeatedKeysAreRefusedPerObjectOnly) {
  // the same key in two sibling objects, or in an object and its child, is fine
  EXPECT_NO_THROW(parse_json_input(R"({"a":{"k":1},"b":{"k":2},"k":[{"k":1},{"k":2}]})", "t.json"));
  EXPECT_THAT([] { parse_json_input(R"({"a":{"k":1},"b":[{"x":1,"k":2,"x":3}]})", "t.json"); },
              ThrowsMessage<InputError>(HasSubstr("t.json: b[].x: duplicate key in one object")));
  EXPECT_THAT([] { parse_json_input(R"({"p":{"k":1,"k":1}})", "t.json", "--params"); },
              ThrowsMessage<InputError>(HasSubstr("t.json: --params.p.k: duplicate key")));
}

TEST(JsonInput, EchoedInputIsCut) {
  // an unterminated string is nlohmann's whole "last read" token; a 100 KB key is the field path
  const auto message = [](const std::string& text) {
    try {
      parse_json_input(text, "t.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string unterminated = message("{\"k\": \"" + std::string(100000, 'a'));
  EXPECT_THAT(unterminated, HasSubstr("t.json: k: not valid JSON: "));
  EXPECT_THAT(unterminated, HasSubstr("more bytes)"));
  EXPECT_LT(unterminated.size(), 400u);
  const std::string key(100000, 'k');
  const std::string duplicate = message("{\"" + key + "\": 1, \"" + key + "\": 2}");
  EXPECT_THAT(duplicate, HasSubstr("duplicate key in one object"));
  EXPECT_LT(duplicate.size(), 400u);
  // an InputError cuts a field path and a reason built from input, never the source
  const InputError e(std::string(300, 's'), std::string(5000, 'f'), std::string(5000, 'r'));
  EXPECT_THAT(std::string(e.what()), HasSubstr(std::string(300, 's') + ": "));
  EXPECT_LT(std::string(e.what()).size(), 300u + 200u + 2000u + 80u);
}

TEST(Contract, TryMakeIsTheNonThrowingTwin) {
  ContractFields f;
  f.scale[2] = -1.0;
  std::string err;
  EXPECT_FALSE(Contract::try_make(f, &err).has_value());
  EXPECT_EQ(err, "scale values must be finite and positive");
  f.scale[2] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(Contract::try_make(f, &err).has_value());
  f.scale[2] = 1.0;
  EXPECT_TRUE(Contract::try_make(f, &err).has_value());
}

}  // namespace
}  // namespace actionshift
