// The grammar rung's additions: the entropy probe of the factorized belief, the scale corrector
// (least-squares fit by Ceres; the public reference implementation's §4.7) and re-anchoring (its §4.8).
#include "actionshift/adapt/grammar_belief.hpp"
#include "actionshift/adapt/registry.hpp"
#include "actionshift/adapt/scale_corrector.hpp"
#include "actionshift/core/decoder.hpp"
#include "actionshift/core/error.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/reference_contracts.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <vector>

namespace actionshift::adapt {
namespace {

using actionshift::testing::intent;
using actionshift::testing::pick_like;
using actionshift::reference::representative_contracts;

// ---- privilege: the corrector is built from the calibrated gains and its options only
using Alpha = std::array<double, kPoseDim>;
static_assert(std::is_constructible_v<ScaleCorrector, Alpha, ScaleCorrectorOptions>);
static_assert(!std::is_constructible_v<ScaleCorrector, Contract>);
static_assert(!std::is_constructible_v<ScaleCorrector, Alpha, Contract>);
static_assert(!std::is_constructible_v<ScaleCorrector, Alpha, ScaleCorrectorOptions, Contract>);
static_assert(!std::is_constructible_v<ScaleCorrector, std::vector<Contract>>);
static_assert(!std::is_constructible_v<GrammarBelief, ResponseModel, std::optional<ScaleCorrectorOptions>, int, Contract>);
static_assert(!std::is_constructible_v<GrammarBelief, ResponseModel, std::optional<ScaleCorrectorOptions>, int, std::vector<Contract>>);

ResponseModel unit_model() { return {{1, 1, 1, 1, 1, 1}, {0.02, 0.02, 0.02, 0.02, 0.02, 0.02}}; }

// ---- the least-squares fit

TEST(ScaleFit, CeresAgreesWithTheClosedForm) {
  Rng rng(7);
  for (int t = 0; t < 25; ++t) {
    std::vector<double> c(16), o(16);
    for (std::size_t k = 0; k < c.size(); ++k) {
      c[k] = std::abs(rng.normal());
      o[k] = 0.03 * (0.5 + rng.uniform()) * c[k] + 0.002 * std::abs(rng.normal());
    }
    const double eff = t % 3 == 0 ? 1.0 : 0.75;
    const double a = fit_window_gain(c, o, 0.03, eff, 0.4, 2.5);
    const double b = fit_window_gain_closed_form(c, o, 0.03, eff, 0.4, 2.5);
    EXPECT_NEAR(a, b, 1e-8 * std::max(1.0, b)) << t;
    EXPECT_GE(a, 0.4);
    EXPECT_LE(a, 2.5);
  }
}

TEST(ScaleFit, RecoversTheTrueGainAndRespectsTheBounds) {
  // encoding with scale g_w executes g_true / g_w of the command: the fit returns g_true
  std::vector<double> c{0.5, 0.2, 0.9, 0.4, 0.7, 0.1, 0.3, 0.8};
  for (double g_true : {0.6, 1.1, 1.9}) {
    std::vector<double> o;
    for (double x : c) o.push_back(0.03 * (g_true / 1.25) * x);
    EXPECT_NEAR(fit_window_gain(c, o, -0.03, 1.25, 0.4, 2.5), g_true, 1e-9) << g_true;  // the sign of α is irrelevant
  }
  std::vector<double> hi, lo;
  for (double x : c) {
    hi.push_back(0.03 * 4.0 * x);
    lo.push_back(0.03 * 0.1 * x);
  }
  EXPECT_DOUBLE_EQ(fit_window_gain(c, hi, 0.03, 1.0, 0.4, 2.5), 2.5);
  EXPECT_DOUBLE_EQ(fit_window_gain(c, lo, 0.03, 1.0, 0.4, 2.5), 0.4);
}

TEST(ScaleFit, RejectsBadInput) {
  const std::vector<double> c{0.5, 0.2}, o{0.01, 0.02}, one{0.1};
  const std::vector<double> nan{0.1, std::nan("")};
  EXPECT_THROW(fit_window_gain(c, one, 0.03, 1.0, 0.4, 2.5), std::invalid_argument);
  EXPECT_THROW(fit_window_gain({}, {}, 0.03, 1.0, 0.4, 2.5), std::invalid_argument);
  EXPECT_THROW(fit_window_gain(c, nan, 0.03, 1.0, 0.4, 2.5), std::invalid_argument);
  EXPECT_THROW(fit_window_gain(c, o, 0.0, 1.0, 0.4, 2.5), std::invalid_argument);
  EXPECT_THROW(fit_window_gain(c, o, 0.03, -1.0, 0.4, 2.5), std::invalid_argument);
  EXPECT_THROW(fit_window_gain(c, o, 0.03, 1.0, 2.5, 0.4), std::invalid_argument);
}

// ---- the online corrector

TEST(ScaleCorrector, CommitsAfterAWindowOfActiveStepsAboveTheFloor) {
  const Alpha alpha{0.03, 0.03, 0.03, 0.03, 0.03, 0.03};
  ScaleCorrector sc(alpha, {8, 0.4, 2.5, 0.02});
  const Pose6 truth = (Pose6() << 1.1, 0.6, 2.0, 1.0, 1.3, 1.0).finished();
  Pose6 base = Pose6::Ones();
  int active = 0;
  for (int k = 0; active < 8; ++k) {
    Pose6 cmd = intent(k).head<kPoseDim>();
    cmd[5] = 0.0;  // channel 5 never commanded: below the floor, never committed
    const Pose6 eff = sc.effective_scale(base);
    const Pose6 obs = 0.03 * cmd.cwiseProduct(truth).cwiseQuotient(eff);
    const bool on = k % 3 != 2;  // every third step is a probe step: ignored
    EXPECT_FALSE(sc.valid(0));
    sc.accumulate(cmd, obs, eff, on);
    active += on ? 1 : 0;
  }
  for (int c = 0; c < 5; ++c) {
    EXPECT_TRUE(sc.valid(c)) << c;
    EXPECT_NEAR(sc.estimate()[c], truth[c], 1e-8) << c;
  }
  EXPECT_FALSE(sc.valid(5));
  EXPECT_EQ(sc.fits(), 5);
  EXPECT_EQ(sc.window_count(), 0);
  EXPECT_NEAR(sc.effective_scale(base)[0], 1.1, 1e-8);
  EXPECT_EQ(sc.effective_scale(base)[5], 1.0);  // not committed: the MAP's scale
  sc.reset();
  EXPECT_FALSE(sc.valid(0));
  EXPECT_EQ(sc.estimate(), Pose6::Ones());
}

int counted_fits = 0;
double counting_fit(std::span<const double> c, std::span<const double> o, double a, double g, double lo, double hi) {
  ++counted_fits;
  return fit_window_gain(c, o, a, g, lo, hi);
}

TEST(ScaleCorrector, TheCeresFitAndTheClosedFormCorrectAlike) {
  // the runner passes the Ceres fit (MethodInputs::gain_fit); without it the closed form is used
  const ResponseModel m = pick_like();
  ContractFields f = representative_contracts("seen")[1].fields();
  for (auto& s : f.scale) s = 1.1;
  const Contract truth = Contract::make(f);
  MethodInputs in;
  in.model = &m;
  in.gain_fit = &counting_fit;
  const auto p = resolve_method_params("grammar_belief", {{"scale_correction", true}, {"scale_window", 8}, {"scale_floor", 0.02}});
  auto with_ceres = make_adapter("grammar_belief", p, in);
  in.gain_fit = nullptr;
  auto closed = make_adapter("grammar_belief", p, in);
  counted_fits = 0;
  for (auto* a : {with_ceres.get(), closed.get()}) {
    Decoder env(truth);
    a->begin_episode(0);
    for (int k = 0; k < 40; ++k) {
      const Action raw = a->encode(intent(k), Mat3::Identity());
      a->observe(raw, m.expected(env.step(raw, Mat3::Identity())), Mat3::Identity());
    }
  }
  EXPECT_GT(counted_fits, 0);  // only the first adapter fitted through the injected function
  const auto& e1 = dynamic_cast<GrammarBeliefAdapter*>(with_ceres.get())->belief().corrector()->estimate();
  const auto& e2 = dynamic_cast<GrammarBeliefAdapter*>(closed.get())->belief().corrector()->estimate();
  for (int c = 0; c < 6; ++c) {
    EXPECT_NEAR(e1[c], e2[c], 1e-7) << c;
    EXPECT_NEAR(e1[c], 1.1, 1e-6) << c;
  }
}

TEST(ScaleCorrector, AChangedEncodingScaleDiscardsTheOpenWindow) {
  ScaleCorrector sc(pick_like().alpha, {4, 0.4, 2.5, 0.0});
  const Pose6 cmd = Pose6::Constant(0.5);
  Pose6 eff = Pose6::Ones();
  for (int k = 0; k < 3; ++k) sc.accumulate(cmd, cmd * 0.01, eff, true);
  EXPECT_EQ(sc.window_count(), 3);
  eff[2] = 1.25;  // the MAP's scale moved
  sc.accumulate(cmd, cmd * 0.01, eff, true);
  EXPECT_EQ(sc.window_count(), 0);
  EXPECT_EQ(sc.fits(), 0);
  for (int k = 0; k < 4; ++k) sc.accumulate(cmd, cmd * 0.01, eff, true);
  EXPECT_EQ(sc.fits(), 6);
}

TEST(ScaleCorrector, OptionsAreValidated) {
  const Alpha a = pick_like().alpha;
  EXPECT_THROW(ScaleCorrector(a, {0, 0.4, 2.5, 0.05}), std::invalid_argument);
  EXPECT_THROW(ScaleCorrector(a, {16, 0.0, 2.5, 0.05}), std::invalid_argument);
  EXPECT_THROW(ScaleCorrector(a, {16, 1.5, 2.5, 0.05}), std::invalid_argument);
  EXPECT_THROW(ScaleCorrector(a, {16, 0.4, 0.9, 0.05}), std::invalid_argument);
  EXPECT_THROW(ScaleCorrector(a, {16, 0.4, std::nan(""), 0.05}), std::invalid_argument);
  EXPECT_THROW(ScaleCorrector(a, {16, 0.4, 2.5, -0.01}), std::invalid_argument);
  Alpha bad = a;
  bad[1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ScaleCorrector(bad, {}), std::invalid_argument);
}

// the grammar belief with the corrector on an off-grid scale
struct Outcome {
  double error{0};
  Contract map{Contract::identity()};
};
Outcome run_adapter(GrammarBeliefAdapter& a, const Contract& truth, const ResponseModel& m, int steps) {
  Decoder env(truth);
  const Mat3 R = Mat3::Identity();
  a.begin_episode(0);
  Outcome out;
  for (int k = 0; k < steps; ++k) {
    const Action want = intent(k);
    const Action raw = a.encode(want, R);
    const Action exec = env.step(raw, R);
    a.observe(raw, m.expected(exec), R);
    if (!a.last_step().probe) out.error = (exec - want).head<6>().norm();
  }
  out.map = a.belief().map().contract;
  return out;
}

TEST(GrammarScaleCorrection, AnOffGridScaleIsCorrected) {
  ContractFields f = representative_contracts("seen")[1].fields();
  for (auto& s : f.scale) s = 1.1;  // between the grid's 1.0 and 1.25
  const Contract truth = Contract::make(f);
  const ResponseModel m = pick_like();
  GrammarBeliefAdapter plain(m);
  GrammarOptions o;
  o.scale = ScaleCorrectorOptions{8, 0.4, 2.5, 0.02};
  GrammarBeliefAdapter corrected(m, o);
  const Outcome p = run_adapter(plain, truth, m, 64);
  const Outcome c = run_adapter(corrected, truth, m, 64);
  EXPECT_GT(p.error, 0.05);  // the nearest grid scale leaves a residual
  EXPECT_LT(c.error, 1e-6);
  ASSERT_TRUE(corrected.belief().corrector().has_value());
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(corrected.belief().corrector()->estimate()[i], 1.1, 1e-6) << i;
  EXPECT_EQ(c.map.permutation(), truth.permutation());
}

TEST(GrammarScaleCorrection, ProbeStepsDoNotTeachTheCorrector) {
  GrammarOptions o;
  o.probe = GrammarProbe::kFixed;
  o.budget = 6;
  o.scale = ScaleCorrectorOptions{8, 0.4, 2.5, 0.0};
  GrammarBeliefAdapter a(pick_like(), o);
  a.begin_episode(0);
  for (int s = 0; s < 6; ++s) a.observe(a.encode(intent(s), Mat3::Identity()), Pose6::Constant(0.01), Mat3::Identity());
  EXPECT_EQ(a.belief().corrector()->window_count(), 0);
  a.observe(a.encode(intent(6), Mat3::Identity()), Pose6::Constant(0.01), Mat3::Identity());
  EXPECT_EQ(a.belief().corrector()->window_count(), 1);
}

// ---- re-anchoring

TEST(GrammarReanchor, TranslationFollowsTheObservedCumulativeResponseEveryPeriod) {
  GrammarBelief b(pick_like(), std::nullopt, 3);
  Pose6 obs_sum = Pose6::Zero(), intent_sum = Pose6::Zero();
  for (int k = 0; k < 6; ++k) {
    b.map_encode(intent(k));
    intent_sum += intent(k).head<kPoseDim>();
    const Pose6 obs = Pose6::Constant(0.01 * (k + 1));
    b.update(intent(k), obs);
    obs_sum += obs;
    if ((k + 1) % 3 == 0) {
      for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(b.tracked_target()[c], obs_sum[c]) << k;
    } else {
      EXPECT_NE(b.tracked_target()[0], obs_sum[0]) << k;
    }
    for (int c = 3; c < 6; ++c) EXPECT_NEAR(b.tracked_target()[c], intent_sum[c], 1e-12);  // rotation keeps the intent
  }
  EXPECT_THROW(GrammarBelief(pick_like(), std::nullopt, -1), std::invalid_argument);
}

// ---- the entropy probe

// An independent, straightforward evaluation of the stated criterion, from the evidence accessors.
double criterion(const GrammarBelief& b, const Action& pulse, const std::array<Pose6, GrammarBelief::kHistory>& hist) {
  const ResponseModel& m = b.model();
  double score = 0;
  for (int i = 0; i < 6; ++i) {
    std::vector<double> logw, pred;
    for (int mode = 0; mode < GrammarBelief::kModes; ++mode) {
      const auto md = GrammarBelief::modes()[static_cast<std::size_t>(mode)];
      for (int j = 0; j < 6; ++j) {
        // history after sending `pulse`: pulse, hist[0], hist[1], ...
        auto h = [&](int d) { return d == 0 ? pulse[j] : hist[static_cast<std::size_t>(d - 1)][j]; };
        const double drive = md.target == Target::kDelta ? h(md.lag) : h(md.lag) - h(md.lag + 1);
        for (int s = 0; s < 2; ++s)
          for (int k = 0; k < 7; ++k) {
            logw.push_back(b.evidence(mode, i, j, s, k));
            pred.push_back(m.alpha[static_cast<std::size_t>(i)] * drive * (s == 0 ? -1.0 : 1.0) * grammar::kScaleGrid[static_cast<std::size_t>(k)]);
          }
      }
    }
    double top = -1e300, z = 0, mean = 0, sq = 0;
    for (double l : logw) top = std::max(top, l);
    for (std::size_t x = 0; x < logw.size(); ++x) {
      const double w = std::exp(logw[x] - top);
      z += w;
      mean += w * pred[x];
      sq += w * pred[x] * pred[x];
    }
    mean /= z;
    const double var = std::max(0.0, sq / z - mean * mean);
    const double sg = m.sigma[static_cast<std::size_t>(i)];
    score += 0.5 * std::log1p(var / (sg * sg));
  }
  return score;
}

TEST(GrammarEntropyProbe, ChoosesThePulseThatMaximisesTheStatedCriterion) {
  const ResponseModel m = pick_like();
  Rng rng(3);
  for (const auto& truth : {representative_contracts("seen")[1], representative_contracts("unseen_composition")[1]}) {
    GrammarBelief b(m);
    Decoder env(truth);
    std::array<Pose6, GrammarBelief::kHistory> hist;
    for (auto& h : hist) h.setZero();
    for (int step = 0; step < 8; ++step) {
      const int q = b.select_entropy_probe(0.5);
      double best = -1;
      int arg = -1;
      for (int c = 0; c < 12; ++c) {
        const double v = criterion(b, GrammarBelief::probe_candidate(c, 0.5), hist);
        if (v > best + 1e-9 * std::abs(best)) {
          best = v;
          arg = c;
        }
      }
      EXPECT_NEAR(criterion(b, GrammarBelief::probe_candidate(q, 0.5), hist), best, 1e-9 * std::max(1.0, best)) << step;
      if (step == 0) {
        EXPECT_EQ(q, arg);  // the fresh belief: every pulse ties, the first wins
      }
      const Action raw = GrammarBelief::probe_candidate(q, 0.5);
      EXPECT_LE(raw.head<6>().cwiseAbs().maxCoeff(), 0.5);
      EXPECT_EQ(raw[6], 0.0);  // the gripper is never actuated
      Pose6 resp = m.expected(env.step(raw, Mat3::Identity()));
      for (int c = 0; c < 6; ++c) resp[c] += 0.5 * m.sigma[static_cast<std::size_t>(c)] * rng.normal();
      b.update(raw, resp);
      for (int d = GrammarBelief::kHistory - 1; d > 0; --d) hist[static_cast<std::size_t>(d)] = hist[static_cast<std::size_t>(d - 1)];
      hist[0] = raw.head<6>();
    }
  }
}

TEST(GrammarEntropyProbe, AfterAChannelIsAnsweredTheNextPulseMovesOn) {
  // +a on raw channel 0, answered by output 0 alone: the other outputs' channel-0 cells are ruled out,
  // so a pulse on channel 0 (either sign) tells them nothing while a pulse elsewhere does; output 0
  // learns as much either way (delta vs absolute: 0 vs −a after any other pulse, a vs 0 or −a vs −2a
  // after a pulse on channel 0)
  GrammarBelief b(unit_model());
  b.update(GrammarBelief::probe_candidate(0, 0.5), (Pose6() << 0.5, 0, 0, 0, 0, 0).finished());
  const int q = b.select_entropy_probe(0.5);
  EXPECT_NE(q % 6, 0) << q;
  std::array<Pose6, GrammarBelief::kHistory> hist;
  for (auto& h : hist) h.setZero();
  hist[0][0] = 0.5;
  EXPECT_GT(criterion(b, GrammarBelief::probe_candidate(1, 0.5), hist), criterion(b, GrammarBelief::probe_candidate(0, 0.5), hist));
}

TEST(GrammarEntropyProbe, TheAdapterProbesThenIdentifies) {
  // A.7's two contracts, noise-free, 20 steps: the entropy variant identifies both like the others
  for (const auto& [mname, model] : {std::pair{"unit", unit_model()}, std::pair{"pick_like", pick_like()}})
    for (const auto& truth : {representative_contracts("seen")[1], representative_contracts("unseen_composition")[1]}) {
      GrammarOptions o;
      o.probe = GrammarProbe::kEntropy;
      GrammarBeliefAdapter a(model, o);
      EXPECT_EQ(a.probe_steps(), 6);
      a.begin_episode(0);
      Decoder env(truth);
      int probes = 0;
      for (int k = 0; k < 20; ++k) {
        const Action raw = a.encode(intent(k), Mat3::Identity());
        probes += a.last_step().probe ? 1 : 0;
        if (a.last_step().probe) {
          EXPECT_LE(raw.head<6>().cwiseAbs().maxCoeff(), 0.5);
          EXPECT_EQ(raw[6], 0.0);
        }
        a.observe(raw, model.expected(env.step(raw, Mat3::Identity())), Mat3::Identity());
      }
      EXPECT_EQ(probes, 6);
      const Contract got = a.belief().map().contract;
      EXPECT_EQ(got.permutation(), truth.permutation()) << mname;
      EXPECT_EQ(got.sign(), truth.sign()) << mname;
      EXPECT_EQ(got.scale(), truth.scale()) << mname;
      EXPECT_EQ(got.target(), truth.target()) << mname;
      EXPECT_EQ(got.lag(), truth.lag()) << mname;
    }
}

// ---- parameters

TEST(GrammarParams, EntropyScaleAndReanchorParameters) {
  const auto p = resolve_method_params("grammar_belief", {{"probe", "entropy"}, {"scale_correction", true}, {"reanchor_period", 8}});
  EXPECT_EQ(p["probe"], "entropy");
  EXPECT_EQ(p["scale_window"], 16);
  EXPECT_EQ(p["scale_min"], 0.4);
  EXPECT_EQ(p["scale_max"], 2.5);
  EXPECT_EQ(p["scale_floor"], 0.05);
  const ResponseModel m = pick_like();
  MethodInputs in;
  in.model = &m;
  auto a = make_adapter("grammar_belief", p, in);
  auto* g = dynamic_cast<GrammarBeliefAdapter*>(a.get());
  ASSERT_NE(g, nullptr);
  EXPECT_TRUE(g->belief().corrector().has_value());
  EXPECT_EQ(g->belief().reanchor_period(), 8);
  EXPECT_EQ(g->probe_steps(), 6);
  auto off = make_adapter("grammar_belief", resolve_method_params("grammar_belief"), in);
  EXPECT_FALSE(dynamic_cast<GrammarBeliefAdapter*>(off.get())->belief().corrector().has_value());
  for (const auto& bad : {nlohmann::json{{"scale_min", 0.0}}, nlohmann::json{{"scale_min", -0.4}}, nlohmann::json{{"scale_min", 1.5}},
                          nlohmann::json{{"scale_max", 0.5}}, nlohmann::json{{"scale_max", std::nan("")}},
                          nlohmann::json{{"scale_floor", -1.0}}, nlohmann::json{{"scale_window", 0}},
                          nlohmann::json{{"scale_window", -16}}, nlohmann::json{{"reanchor_period", -1}},
                          nlohmann::json{{"scale_correction", "yes"}}, nlohmann::json{{"scale_windw", 16}}})
    EXPECT_THROW(resolve_method_params("grammar_belief", bad), InputError) << bad.dump();
}

}  // namespace
}  // namespace actionshift::adapt
