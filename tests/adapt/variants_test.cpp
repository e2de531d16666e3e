// A method's bare name is the paper's method; its variants are labels of their own (the honest-verdicts
// issue): the registry's defaults of entropy_probes and dualabi are the reference's selection rule, the
// project's corrections are the named variant `calibrated`, and labels round-trip canonically.
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/plugin.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "synthetic.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace actionshift::adapt {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using actionshift::testing::intent;
using actionshift::testing::pick_like;

TEST(MethodDefaults, EntropyAndDualAbiRunThePapersRule) {
  const auto e = resolve_method_params("entropy_probes");
  EXPECT_EQ(e.at("calibrated_preview"), false);
  EXPECT_EQ(e.at("lag_aware_preview"), false);
  EXPECT_EQ(e.at("entropy_tolerance").get<double>(), 0.0);
  EXPECT_EQ(e.at("motion_tiebreak"), false);
  const auto d = resolve_method_params("dualabi");
  EXPECT_EQ(d.at("calibrated_preview"), false);
  EXPECT_EQ(d.at("lag_aware_preview"), false);
  // the struct's defaults, on which the Appendix A.4 parity tests run, are the same rule
  const ProbeOptions o;
  EXPECT_FALSE(o.calibrated_preview);
  EXPECT_FALSE(o.lag_aware_preview);
  EXPECT_EQ(o.entropy_tolerance, 0.0);
  EXPECT_FALSE(o.motion_tiebreak);
}

// the probe sequence an adapter sends on a synthetic pick-like episode
std::vector<Action> probes_of(Adapter& a, const Contract& truth) {
  Decoder env(truth);
  Rng rng(7);
  a.begin_episode(1);
  std::vector<Action> out;
  for (int k = 0; k < 8; ++k) {
    const Action raw = a.encode(intent(k), Mat3::Identity());
    if (a.last_step().probe) out.push_back(raw);
    Pose6 resp = pick_like().expected(env.step(raw));
    for (int c = 0; c < 6; ++c) resp[c] += pick_like().sigma[static_cast<std::size_t>(c)] * rng.normal();
    a.observe(raw, resp, Mat3::Identity());
  }
  return out;
}

TEST(MethodDefaults, TheRegistrysEntropyProbesIsTheStructDefaultAndTheVariantDiffers) {
  const ResponseModel model = pick_like();
  MethodInputs in;
  const auto pool = reference::pool9();
  in.pool = &pool;
  in.model = &model;
  int differ = 0;
  for (std::size_t t = 1; t < pool.size(); ++t) {
    auto by_name = make_adapter("entropy_probes", resolve_method_params("entropy_probes"), in);
    ProbingAdapter by_struct(pool, model, ProbeStrategy::kEntropy, ProbeOptions{});
    const auto a = probes_of(*by_name, pool[t]);
    EXPECT_EQ(a, probes_of(by_struct, pool[t])) << "truth " << t;
    const MethodLabel v = parse_method_label("entropy_probes{calibrated}");
    auto variant = make_adapter(v.name, resolve_method_params(v.name, v.params), in);
    differ += probes_of(*variant, pool[t]) != a ? 1 : 0;
  }
  EXPECT_GT(differ, 0) << "the calibrated variant never chose another probe: it would not be a variant";
}

TEST(MakeAdapter, UnresolvedParametersTakeDefaultsAndBadOnesAreOneLineErrors) {
  // a C++ integrator calling make_adapter directly: {} is the paper's method (it was a raw JSON
  // exception, "key 'budget' not found"); a bad value names the method and the field on one line
  const ResponseModel model = pick_like();
  MethodInputs in;
  const auto pool = reference::pool9();
  in.pool = &pool;
  in.model = &model;
  auto partial = make_adapter("entropy_probes", nlohmann::json::object(), in);
  auto resolved = make_adapter("entropy_probes", resolve_method_params("entropy_probes"), in);
  EXPECT_EQ(probes_of(*partial, pool[3]), probes_of(*resolved, pool[3]));
  auto one_line = [](const std::string& field) {
    return ThrowsMessage<InputError>(::testing::AllOf(HasSubstr("method entropy_probes: " + field),
                                                      ::testing::Not(HasSubstr("\n"))));
  };
  EXPECT_THAT([&] { make_adapter("entropy_probes", {{"budget", "six"}}, in); }, one_line("budget: wrong type"));
  EXPECT_THAT([&] { make_adapter("entropy_probes", {{"budget", -1}}, in); }, one_line("budget: must be in [0, 1000]"));
  EXPECT_THAT([&] { make_adapter("entropy_probes", {{"budgte", 6}}, in); }, one_line("budgte: unknown parameter"));
  EXPECT_THAT([&] { make_adapter("dualabi", {{"tau", 1.5}}, MethodInputs{}); },
              ThrowsMessage<InputError>(HasSubstr("needs a pool")));
}

TEST(MakeAdapter, TheDelayedOracleIsOnTheOracleRungAndChecksItsParameters) {
  // a diagnostic beside the paper's methods: the truth is its privilege, as the oracle's, and nothing else
  EXPECT_EQ(method_rung("delayed_oracle"), Rung::oracle);
  EXPECT_FALSE(method_needs_pool("delayed_oracle"));
  EXPECT_FALSE(method_needs_calibration("delayed_oracle"));
  EXPECT_EQ(resolve_method_params("delayed_oracle"), (nlohmann::json{{"delay", 6}, {"before", "no_adapt"}}));
  const Contract truth = reference::representative_contracts("seen")[1];
  MethodInputs in;
  in.truth = &truth;
  EXPECT_EQ(make_adapter("delayed_oracle", {{"delay", 2}, {"before", "hold"}}, in)->name(), "delayed_oracle");
  auto one_line = [](const std::string& what) {
    return ThrowsMessage<InputError>(::testing::AllOf(HasSubstr(what), ::testing::Not(HasSubstr("\n"))));
  };
  EXPECT_THAT([&] { make_adapter("delayed_oracle", nlohmann::json::object(), MethodInputs{}); }, one_line("needs the true contract"));
  EXPECT_THAT([&] { make_adapter("delayed_oracle", {{"delay", -1}}, in); }, one_line("method delayed_oracle: delay: must be in"));
  EXPECT_THAT([&] { make_adapter("delayed_oracle", {{"before", "probe"}}, in); },
              one_line("method delayed_oracle: before: must be one of no_adapt, hold"));
}

TEST(MethodLabels, CanonicalLabelsRoundTrip) {
  const auto label = [](const std::string& text) {
    const MethodLabel l = parse_method_label(text);
    return method_variant_label(l.name, resolve_method_params(l.name, l.params));
  };
  EXPECT_EQ(label("entropy_probes"), "entropy_probes");
  EXPECT_EQ(label("entropy_probes{}"), "entropy_probes");
  EXPECT_EQ(label("entropy_probes{budget=6}"), "entropy_probes");  // the default is no variant
  EXPECT_EQ(label("entropy_probes{calibrated}"), "entropy_probes{calibrated}");
  EXPECT_EQ(label("entropy_probes{calibrated_preview=true,lag_aware_preview=true,entropy_tolerance=0.001,motion_tiebreak=true}"),
            "entropy_probes{calibrated}");
  EXPECT_EQ(label("entropy_probes{calibrated, budget=12}"), "entropy_probes{calibrated,budget=12}");
  EXPECT_EQ(label("entropy_probes{motion_tiebreak=false,calibrated_preview=true}"), "entropy_probes{calibrated_preview=true}");
  EXPECT_EQ(label("dualabi{calibrated}"), "dualabi{calibrated}");
  EXPECT_EQ(label("dualabi{tau=0.5}"), "dualabi{tau=0.5}");
  EXPECT_EQ(label("dualabi{tau=1.5}"), "dualabi");
  EXPECT_EQ(label("dualabi{tau=2}"), "dualabi{tau=2.0}");  // an integer for a real parameter is that real
  EXPECT_EQ(label("dualabi{tau=1.5,calibrated_preview=true,lag_aware_preview=true}"), "dualabi{calibrated}");
  EXPECT_EQ(label("grammar_belief{probe=hold}"), "grammar_belief{probe=hold}");
  EXPECT_EQ(label("oracle"), "oracle");
  // a variant overridden back to the default of one of its keys is that key, not the variant
  EXPECT_EQ(label("entropy_probes{calibrated,motion_tiebreak=false}"),
            "entropy_probes{calibrated_preview=true,entropy_tolerance=0.001,lag_aware_preview=true}");
  // every canonical label parses back to itself
  for (const char* text : {"entropy_probes{calibrated,budget=12}", "grammar_belief{probe=hold}", "dualabi{tau=0.5}"})
    EXPECT_EQ(label(label(text)), label(text));
}

TEST(MethodLabels, MalformedLabelsAreOneLineErrors) {
  EXPECT_THAT([] { parse_method_label("entropy_probes{nope}"); }, ThrowsMessage<InputError>(HasSubstr("unknown variant (known: calibrated)")));
  EXPECT_THAT([] { parse_method_label("fixed_probes{calibrated}"); }, ThrowsMessage<InputError>(HasSubstr("this method has no named variants")));
  EXPECT_THAT([] { parse_method_label("entropy_probes{budget=3,budget=4}"); }, ThrowsMessage<InputError>(HasSubstr("given twice")));
  EXPECT_THAT([] { parse_method_label("entropy_probes{budget=3"); }, ThrowsMessage<InputError>(HasSubstr("end with '}'")));
  EXPECT_THAT([] { parse_method_label("{budget=3}"); }, ThrowsMessage<InputError>(HasSubstr("no method name")));
  EXPECT_THAT([] { parse_method_label("entropy_probes{budget=}"); }, ThrowsMessage<InputError>(HasSubstr("missing value")));
  EXPECT_THAT([] { parse_method_label("entropy_probes{budget=3,calibrated}"); }, ThrowsMessage<InputError>(HasSubstr("comes first")));
  // a value of the wrong type is the registry's error, naming the parameter
  EXPECT_THAT([] {
    const MethodLabel l = parse_method_label("entropy_probes{budget=1.5}");
    resolve_method_params(l.name, l.params);
  }, ThrowsMessage<InputError>(HasSubstr("budget: wrong type")));
  // a label and explicit params that disagree
  EXPECT_THAT([] { merge_method_params(parse_method_label("entropy_probes{budget=3}"), {{"budget", 4}}); },
              ThrowsMessage<InputError>(HasSubstr("set to 3 by the label and to 4 by params")));
  EXPECT_NO_THROW(merge_method_params(parse_method_label("entropy_probes{budget=3}"), {{"budget", 3}}));
}

}  // namespace
}  // namespace actionshift::adapt
