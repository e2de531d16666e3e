#include "actionshift/adapt/calibration.hpp"
#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/adapt/methods.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace actionshift::adapt {
namespace {

using actionshift::testing::intent;
using actionshift::testing::pick_like;
using actionshift::reference::representative_contracts;

// ---- privilege: the grammar and the calibration only (the reference implementation's privilege invariant)

static_assert(std::is_constructible_v<GrammarBeliefAdapter, ResponseModel, GrammarOptions>);
static_assert(std::is_constructible_v<GrammarBelief, ResponseModel>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, Contract>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, Contract, ResponseModel>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, ResponseModel, Contract>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, std::vector<Contract>, ResponseModel>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, ResponseModel, std::vector<Contract>>);
static_assert(!std::is_constructible_v<GrammarBeliefAdapter, ResponseModel, GrammarOptions, Contract>);
static_assert(!std::is_constructible_v<GrammarBelief, Contract>);
static_assert(!std::is_constructible_v<GrammarBelief, std::vector<Contract>, ResponseModel>);
static_assert(!std::is_constructible_v<GrammarBelief, ResponseModel, Contract>);
static_assert(!std::is_constructible_v<HoldSchedule, Contract>);

ResponseModel unit_model() { return {{1, 1, 1, 1, 1, 1}, {0.02, 0.02, 0.02, 0.02, 0.02, 0.02}}; }

TEST(GrammarBeliefPrivilege, RegistryBuildsItFromTheCalibrationAlone) {
  EXPECT_FALSE(method_needs_pool("grammar_belief"));
  EXPECT_TRUE(method_needs_calibration("grammar_belief"));
  const ResponseModel m = pick_like();
  MethodInputs in;  // no truth, no pool
  in.model = &m;
  const auto a = make_adapter("grammar_belief", resolve_method_params("grammar_belief"), in);
  EXPECT_EQ(a->name(), "grammar_belief");
  MethodInputs none;
  EXPECT_THROW(make_adapter("grammar_belief", resolve_method_params("grammar_belief"), none), InputError);
}

// ---- Appendix A.7

TEST(GrammarBelief, ReferenceA7FreshMap) {
  GrammarBelief b(pick_like());
  const auto& map = b.map();
  EXPECT_EQ(map.contract.permutation(), (std::array<int, 6>{0, 1, 2, 3, 4, 5}));
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(map.contract.sign()[static_cast<std::size_t>(i)], -1);
    EXPECT_EQ(map.contract.scale()[static_cast<std::size_t>(i)], 0.5);
  }
  EXPECT_EQ(map.contract.target(), Target::kDelta);
  EXPECT_EQ(map.contract.lag(), 0);
  EXPECT_FALSE(map.contract.gripper_inverted());
  Action c;
  c << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7;
  const Action raw = b.map_encode(c);
  const double want[7] = {-0.2, -0.4, -0.6, -0.8, -1.0, -1.2, 0.7};
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(raw[k], want[k], 1e-12) << k;
  EXPECT_NEAR(b.tracked_target()[5], 0.6, 1e-15);  // the tracked target is the cumulative intent
}

struct Trace {
  Contract map;
  double last_error{0};
  int probes{0};
};

Trace run(GrammarBeliefAdapter& a, const Contract& truth, const ResponseModel& m, int steps, double noise = 0.0,
        std::uint64_t seed = 1) {
  Decoder env(truth);
  Rng rng(seed);
  const Mat3 R = Mat3::Identity();
  a.begin_episode(seed);
  Trace out{Contract::identity()};
  for (int k = 0; k < steps; ++k) {
    const Action want = intent(k);
    const Action raw = a.encode(want, R);
    out.probes += a.last_step().probe ? 1 : 0;
    const Action exec = env.step(raw, R);
    Pose6 resp = m.expected(exec);
    for (int c = 0; c < 6; ++c) resp[c] += noise * m.sigma[static_cast<std::size_t>(c)] * rng.normal();
    a.observe(raw, resp, R);
    if (!a.last_step().probe) out.last_error = (exec - want).head<6>().norm();
  }
  out.map = a.belief().map().contract;
  return out;
}

void expect_pose_fields(const Contract& got, const Contract& truth, const std::string& what) {
  EXPECT_EQ(got.permutation(), truth.permutation()) << what;
  EXPECT_EQ(got.sign(), truth.sign()) << what;
  EXPECT_EQ(got.scale(), truth.scale()) << what;
  EXPECT_EQ(got.target(), truth.target()) << what;
  EXPECT_EQ(got.lag(), truth.lag()) << what;
}

GrammarOptions with_probe(GrammarProbe p) {
  GrammarOptions o;
  o.probe = p;
  return o;
}

TEST(GrammarBelief, ReferenceA7NoiseFreeRecovery) {
  // seen[1] (delta) and unseen_composition[1] (absolute, lag 0) over 20 steps, passive, 6 fixed
  // pulses and h2-r1 hold probing, with α = 1 / σ = 0.02 and with the pick-like α / σ
  const Contract seen1 = representative_contracts("seen")[1];
  const Contract abs1 = representative_contracts("unseen_composition")[1];
  for (const auto& [mname, model] : {std::pair{"unit", unit_model()}, std::pair{"pick_like", pick_like()}})
    for (const auto& truth : {seen1, abs1})
      for (auto p : {GrammarProbe::kNone, GrammarProbe::kFixed, GrammarProbe::kHold}) {
        GrammarBeliefAdapter a(model, with_probe(p));
        const Trace r = run(a, truth, model, 20);
        expect_pose_fields(r.map, truth,
                           std::string(mname) + " " + to_string(truth.target()) + " probe " + std::to_string(static_cast<int>(p)));
        EXPECT_EQ(r.map.frame(), Frame::kBase);
        EXPECT_FALSE(r.map.gripper_inverted());  // unobservable without a finger channel
        EXPECT_EQ(r.probes, p == GrammarProbe::kNone ? 0 : (p == GrammarProbe::kFixed ? 6 : 12));
      }
}

TEST(GrammarBelief, ReachesParityOnDeltaAndAbsolute) {
  const ResponseModel m = pick_like();
  for (const auto& truth : {representative_contracts("seen")[1], representative_contracts("unseen_composition")[1]}) {
    GrammarBeliefAdapter a(m);
    const Trace r = run(a, truth, m, 48, 0.0);
    EXPECT_LT(r.last_error, 1e-9) << to_string(truth.target());
  }
}

TEST(GrammarBelief, IdentifiesRandomFullGrammarContractsWithNoise) {
  // the reference implementation's identification invariant: random delta and absolute contracts (lags on the grid) within 48 steps
  const ResponseModel m = unit_model();
  Rng rng(20260718);
  grammar::SamplerSpec spec;
  spec.targets = {"delta", "absolute"};
  spec.lags = {0, 1, 2, 4};
  spec.gripper_inverted = {false};
  int identified = 0;
  for (int t = 0; t < 12; ++t) {
    const Contract truth = grammar::sample(spec, rng);
    GrammarBeliefAdapter a(m);
    const Trace r = run(a, truth, m, 48, 1.0, static_cast<std::uint64_t>(t));
    const bool ok = r.map.permutation() == truth.permutation() && r.map.sign() == truth.sign() &&
                    r.map.scale() == truth.scale() && r.map.target() == truth.target() && r.map.lag() == truth.lag();
    identified += ok ? 1 : 0;
  }
  EXPECT_GE(identified, 11);
}

TEST(GrammarBelief, TrueCellCarriesNoEvidenceAgainstIt) {
  // noise-free: the truth's cells predict every response exactly (evidence 0, the maximum)
  const Contract truth = representative_contracts("seen")[1];
  const ResponseModel m = pick_like();
  GrammarBelief b(m);
  Decoder env(truth);
  for (int k = 0; k < 10; ++k) {
    const Action raw = intent(k) * 0.7;
    b.update(raw, m.expected(env.step(raw, Mat3::Identity())));
  }
  double worst = -std::numeric_limits<double>::infinity();
  for (int m8 = 0; m8 < GrammarBelief::kModes; ++m8)
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        for (int s = 0; s < 2; ++s)
          for (int k = 0; k < 7; ++k) worst = std::max(worst, b.evidence(m8, i, j, s, k));
  EXPECT_LE(worst, 0.0);
  for (int i = 0; i < 6; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    int k = 0;
    while (grammar::kScaleGrid[static_cast<std::size_t>(k)] != truth.scale()[ii]) ++k;
    EXPECT_NEAR(b.evidence(0, i, truth.permutation()[ii], truth.sign()[ii] > 0 ? 1 : 0, k), 0.0, 1e-9) << i;
  }
}

TEST(GrammarBelief, DriveIsTheLaggedRawOrItsDifference) {
  GrammarBelief b(unit_model());
  for (int k = 0; k < 6; ++k) {
    Action raw = Action::Zero();
    raw[0] = k + 1.0;  // 1, 2, ..., 6 (history 6, 5, 4, 3, 2, 1)
    b.update(raw, Pose6::Zero());
  }
  EXPECT_EQ(b.drive(0, 0), 6.0);  // delta lag 0
  EXPECT_EQ(b.drive(2, 0), 4.0);  // delta lag 2
  EXPECT_EQ(b.drive(3, 0), 2.0);  // delta lag 4
  EXPECT_EQ(b.drive(4, 0), 1.0);  // absolute lag 0: 6 − 5
  EXPECT_EQ(b.drive(7, 0), 1.0);  // absolute lag 4: 2 − 1
  b.reset();
  EXPECT_EQ(b.drive(4, 0), 0.0);
}

TEST(GrammarBelief, PerModeObservationsScoreEachModeOnItsOwn) {
  // the same observation for every mode is update(); a different one for mode 5 changes only mode 5's cells
  GrammarBelief one(unit_model()), per(unit_model()), moved(unit_model());
  for (int k = 0; k < 8; ++k) {
    Action raw = Action::Zero();
    for (int j = 0; j < kPoseDim; ++j) raw[j] = std::sin(0.7 * k + j);
    Pose6 obs;
    for (int j = 0; j < kPoseDim; ++j) obs[j] = std::cos(0.3 * k - j);
    std::array<Pose6, GrammarBelief::kModes> same;
    same.fill(obs);
    one.update(raw, obs);
    per.update_per_mode(raw, same);
    same[5] = obs * 2.0;
    moved.update_per_mode(raw, same);
  }
  for (int m = 0; m < GrammarBelief::kModes; ++m)
    for (int i = 0; i < kPoseDim; ++i)
      for (int j = 0; j < kPoseDim; ++j)
        for (int s = 0; s < GrammarBelief::kSigns; ++s)
          for (int k = 0; k < GrammarBelief::kScales; ++k) {
            EXPECT_EQ(per.evidence(m, i, j, s, k), one.evidence(m, i, j, s, k));
            if (m != 5) {
              EXPECT_EQ(moved.evidence(m, i, j, s, k), one.evidence(m, i, j, s, k));
            }
          }
  EXPECT_NE(moved.evidence(5, 0, 0, 0, 0), one.evidence(5, 0, 0, 0, 0));
  // one observation per step is the only way into a belief that corrects its scale or re-anchors
  GrammarBelief anchored(unit_model(), std::nullopt, 10);
  std::array<Pose6, GrammarBelief::kModes> zeros{};
  EXPECT_THROW(anchored.update_per_mode(Action::Zero(), zeros), std::logic_error);
}

TEST(HoldSchedule, ScheduleAndValidation) {
  const HoldSchedule h(0.5, 4, 2, 6);
  EXPECT_EQ(h.total_steps(), 48);
  for (int s = 0; s < 4; ++s) EXPECT_EQ(h.action(s)[0], 0.5);
  for (int s = 4; s < 8; ++s) EXPECT_EQ(h.action(s)[1], 0.5);
  EXPECT_EQ(h.action(3).cwiseAbs().sum(), 0.5);
  EXPECT_EQ(h.action(3)[6], 0.0);
  EXPECT_TRUE(h.is_window_close(3));
  EXPECT_TRUE(h.is_window_close(7));
  EXPECT_FALSE(h.is_window_close(4));
  EXPECT_EQ(HoldSchedule().version(), "holdv1-a0.5-h2-r1-c6");
  EXPECT_EQ(HoldSchedule().total_steps(), 12);
  EXPECT_THROW(HoldSchedule(0.5, 1, 1, 6), std::invalid_argument);
  EXPECT_THROW(HoldSchedule(0.5, 2, 0, 6), std::invalid_argument);
  EXPECT_THROW(HoldSchedule(0.5, 2, 1, 7), std::invalid_argument);
  EXPECT_THROW(HoldSchedule(std::nan(""), 2, 1, 6), std::invalid_argument);
  EXPECT_THROW(HoldSchedule(-0.5, 2, 1, 6), std::invalid_argument);
}

TEST(HoldProbe, WindowEvidenceSeparatesAbsoluteFromDelta) {
  // a held pulse: an absolute drive telescopes (Σ response = one excursion), a delta drive
  // accumulates len × command; after one window the absolute mode leads
  const ResponseModel m = unit_model();
  Contract truth = representative_contracts("unseen_composition")[1];
  GrammarBelief b(m);
  Decoder env(truth);
  const HoldSchedule h;
  for (int s = 0; s < h.total_steps(); ++s) {
    const Action raw = h.action(s);
    b.update(raw, m.expected(env.step(raw, Mat3::Identity())), true, h.is_window_close(s));
    EXPECT_EQ(b.hold_length(), h.is_window_close(s) ? 0 : (s % 2) + 1);
  }
  expect_pose_fields(b.map().contract, truth, "hold only");
  GrammarBelief passive(m);
  passive.update(Action::Zero(), Pose6::Zero());
  EXPECT_EQ(passive.hold_length(), 0);  // no hold mask: the accumulators stay untouched
}

TEST(GrammarProbing, FixedEmitsBudgetBoundedPulsesThenControls) {
  GrammarOptions o = with_probe(GrammarProbe::kFixed);
  o.budget = 4;
  GrammarBeliefAdapter a(pick_like(), o);
  a.begin_episode(0);
  for (int s = 0; s < 8; ++s) {
    const Action raw = a.encode(intent(s), Mat3::Identity());
    EXPECT_EQ(a.last_step().probe, s < 4);
    if (s < 4) {
      EXPECT_EQ(raw, fixed_probe_pulse(s, 0.5));
      EXPECT_EQ(raw[6], 0.0);
    }
    a.observe(raw, Pose6::Zero(), Mat3::Identity());
  }
  a.begin_episode(1);  // the next episode probes again
  a.encode(intent(0), Mat3::Identity());
  EXPECT_TRUE(a.last_step().probe);
}

TEST(GrammarProbing, FlailThenIdentitySendsTheIntentUnchanged) {
  GrammarOptions o = with_probe(GrammarProbe::kHold);
  o.belief_after_probe = false;
  GrammarBeliefAdapter a(pick_like(), o);
  const Trace r = run(a, representative_contracts("unseen_composition")[1], pick_like(), 20);
  EXPECT_EQ(r.probes, 12);
  a.begin_episode(0);
  for (int s = 0; s < 12; ++s) a.observe(a.encode(intent(s), Mat3::Identity()), Pose6::Zero(), Mat3::Identity());
  EXPECT_EQ(a.encode(intent(12), Mat3::Identity()), intent(12));
}

TEST(GrammarParams, DefaultsAndMalformed) {
  const auto p = resolve_method_params("grammar_belief");
  EXPECT_EQ(p.dump(),
            R"({"after_probe":"belief","amplitude":0.5,"budget":6,"gripper_channel":false,"hold_channels":6,"hold_rounds":1,"hold_steps":2,"probe":"none",)"
            R"("reanchor_period":0,"scale_correction":false,"scale_floor":0.05,"scale_max":2.5,"scale_min":0.4,"scale_window":16})");
  EXPECT_EQ(resolve_method_params("grammar_belief", {{"probe", "hold"}, {"hold_rounds", 2}})["hold_rounds"], 2);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"pool", "full"}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"probe", "entropyish"}}), InputError);
  EXPECT_NO_THROW(resolve_method_params("grammar_belief", {{"probe", "entropy"}}));
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"probe", 1}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"hold_steps", -2}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"hold_steps", 1}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"hold_channels", 7}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"budget", -1}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"amplitude", std::nan("")}}), InputError);
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"after_probe", "nothing"}}), InputError);
}

TEST(MethodParams, IntegersBeyondAnIntAreRejectedNotWrappedAndSizesAreBounded) {
  // 2**32 + 3 used to pass the [0, 1000] check as 3 while the job recorded 4294967299
  for (const char* m : {"fixed_probes", "grammar_belief"}) {
    EXPECT_THROW(resolve_method_params(m, {{"budget", 4294967299ULL}}), InputError) << m;
    EXPECT_THROW(resolve_method_params(m, {{"budget", std::int64_t{-4294967296}}}), InputError) << m;
  }
  EXPECT_THROW(resolve_method_params("grammar_belief", {{"hold_rounds", 4294967297LL}}), InputError);
  EXPECT_THROW(resolve_method_params("osi", {{"warmup", 4294967304LL}}), InputError);
  // DualABI's window and the active set are bounded: 10**7 took 5.8 GB to build
  EXPECT_THROW(resolve_method_params("dualabi", {{"window", 10000000}}), InputError);
  EXPECT_EQ(resolve_method_params("dualabi", {{"window", 1000}})["window"], 1000);
  EXPECT_THROW(resolve_method_params("entropy_probes", {{"max_active", 1 << 20}}), InputError);
  EXPECT_EQ(resolve_method_params("fixed_probes", {{"budget", 1000}})["budget"], 1000);
}

TEST(GrammarBelief, ANonFiniteIntentDoesNotPoisonTheTrackedTarget) {
  const ResponseModel m = pick_like();
  MethodInputs in;
  in.model = &m;
  const auto a = make_adapter("grammar_belief", resolve_method_params("grammar_belief"), in);
  a->begin_episode(1);
  a->encode(Action::Constant(std::numeric_limits<double>::quiet_NaN()), Mat3::Identity());
  for (int s = 0; s < 5; ++s) EXPECT_TRUE(a->encode(intent(s), Mat3::Identity()).allFinite()) << "step " << s;
}


// ---- the finger channel (the public reference implementation's finger channel, docs/reference.md)

TEST(GrammarGripper, FingerChannelIdentifiesInversion) {
  // the reference implementation's finger-channel invariant: α_g 0.05, σ_g 0.01, inversion true and false identified after 32 steps
  ResponseModel m = unit_model();
  m.gripper_alpha = 0.05;
  m.gripper_sigma = 0.01;
  for (bool inverted : {false, true}) {
    ContractFields f;
    f.permutation = {2, 0, 1, 3, 5, 4};
    f.gripper_inverted = inverted;
    const Contract truth = Contract::make(f);
    GrammarOptions o;
    o.gripper_channel = true;
    GrammarBeliefAdapter a(m, o);
    Decoder env(truth);
    Rng rng(7);
    a.begin_episode(0);
    for (int k = 0; k < 32; ++k) {
      const Action raw = a.encode(intent(k), Mat3::Identity());
      const Action exec = env.step(raw, Mat3::Identity());
      a.observe_fingers(m.gripper_alpha * exec[6] + m.gripper_sigma * rng.normal());
      a.observe(raw, m.expected(exec), Mat3::Identity());
    }
    EXPECT_EQ(a.belief().map().contract.gripper_inverted(), inverted);
    EXPECT_NE(a.belief().gripper_score(0), a.belief().gripper_score(1));
    a.begin_episode(1);  // the scores reset with the episode
    EXPECT_EQ(a.belief().gripper_score(0), 0.0);
    EXPECT_EQ(a.belief().gripper_score(1), 0.0);
  }
}

TEST(GrammarGripper, ChannelOffIgnoresFingersAndNeedsCalibration) {
  ResponseModel m = unit_model();
  EXPECT_THROW(GrammarBeliefAdapter(m, GrammarOptions{.gripper_channel = true}), std::invalid_argument);
  MethodInputs in;
  in.model = &m;
  EXPECT_THROW(make_adapter("grammar_belief", resolve_method_params("grammar_belief", {{"gripper_channel", true}}), in),
               InputError);
  m.gripper_alpha = 0.05;
  m.gripper_sigma = 0.01;
  GrammarBeliefAdapter a(m);  // channel off: finger evidence is not scored
  a.begin_episode(0);
  for (int k = 0; k < 8; ++k) {
    const Action raw = a.encode(intent(k), Mat3::Identity());
    a.observe_fingers(-0.05 * raw[6]);
    a.observe(raw, Pose6::Zero(), Mat3::Identity());
  }
  EXPECT_EQ(a.belief().gripper_score(1), 0.0);
  EXPECT_FALSE(a.belief().map().contract.gripper_inverted());
}

TEST(GrammarGripper, CalibrationKeyIsOptionalAndRoundTrips) {
  ResponseCalibration c;
  c.task = "pick_cube";
  c.slice = {19, 22};
  c.fit.alpha = {0.03, 0.02, 0.02, -0.03, -0.03, -0.04};
  c.fit.sigma = {0.02, 0.02, 0.02, 0.04, 0.05, 0.04};
  c.episodes = 8;
  c.steps = 64;
  c.seed = 20260720;
  const std::string plain = c.to_json();
  EXPECT_EQ(plain.find("gripper"), std::string::npos);  // files without the channel hash as before
  EXPECT_FALSE(c.model().has_gripper());
  c.gripper = fit_gripper_response({1.0, -1.0, 0.5, -0.5}, {0.0093, -0.0093, 0.00465, -0.00465}, 7);
  EXPECT_NEAR(c.gripper->alpha, 0.0093, 1e-12);
  EXPECT_NEAR(c.gripper->fit_r2, 1.0, 1e-12);
  const ResponseCalibration back = ResponseCalibration::from_json(c.to_json(), "t");
  ASSERT_TRUE(back.gripper.has_value());
  EXPECT_EQ(back.gripper->start, 7);
  EXPECT_EQ(back.to_json(), c.to_json());
  EXPECT_NE(back.sha256(), ResponseCalibration::from_json(plain, "t").sha256());
  EXPECT_TRUE(back.model().has_gripper());
  std::string bad = c.to_json();
  bad.replace(bad.find("\"start\":7"), 9, "\"start\":-1");
  EXPECT_THROW(ResponseCalibration::from_json(bad, "t"), InputError);
}

}  // namespace
}  // namespace actionshift::adapt
