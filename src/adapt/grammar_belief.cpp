#include "actionshift/adapt/grammar_belief.hpp"

#include "actionshift/adapt/methods.hpp"
#include "actionshift/core/grammar.hpp"
#include "actionshift/core/transforms.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace actionshift::adapt {

// ---- HoldSchedule

HoldSchedule::HoldSchedule(double amplitude, int hold_steps, int rounds, int channels)
    : amplitude_(amplitude), hold_steps_(hold_steps), rounds_(rounds), channels_(channels) {
  if (!std::isfinite(amplitude) || !(amplitude > 0.0 && amplitude <= 1.0))
    throw std::invalid_argument("hold amplitude must be finite and in (0, 1]");
  if (hold_steps < 2 || hold_steps > 1000) throw std::invalid_argument("hold_steps must be in [2, 1000]");
  if (rounds < 1 || rounds > 1000) throw std::invalid_argument("hold rounds must be in [1, 1000]");
  if (channels < 1 || channels > kPoseDim) throw std::invalid_argument("hold channels must be in [1, 6]");
}

Action HoldSchedule::action(int step) const {
  Action a = Action::Zero();
  a[(step / hold_steps_) % channels_] = amplitude_;
  return a;
}

std::string HoldSchedule::version() const {
  std::ostringstream s;
  s << "holdv1-a" << amplitude_ << "-h" << hold_steps_ << "-r" << rounds_ << "-c" << channels_;
  return s.str();
}

// ---- GrammarBelief

const std::array<GrammarBelief::Mode, GrammarBelief::kModes>& GrammarBelief::modes() {
  static const std::array<Mode, kModes> m{{{Target::kDelta, 0},
                                           {Target::kDelta, 1},
                                           {Target::kDelta, 2},
                                           {Target::kDelta, 4},
                                           {Target::kAbsolute, 0},
                                           {Target::kAbsolute, 1},
                                           {Target::kAbsolute, 2},
                                           {Target::kAbsolute, 4}}};
  return m;
}

GrammarBelief::GrammarBelief(const ResponseModel& model, std::optional<ScaleCorrectorOptions> scale, int reanchor_period)
    : model_(model), reanchor_period_(reanchor_period) {
  model_.validate();
  if (reanchor_period < 0) throw std::invalid_argument("reanchor_period must be nonnegative");
  if (scale) corrector_.emplace(model_.alpha, *scale);
  for (int s = 0; s < kSigns; ++s)
    for (int k = 0; k < kScales; ++k)
      coef_[static_cast<std::size_t>(s * kScales + k)] = (s == 0 ? -1.0 : 1.0) * grammar::kScaleGrid[static_cast<std::size_t>(k)];
  reset();
}

void GrammarBelief::reset() {
  S_.fill(0.0);
  for (auto& h : history_) h.setZero();
  for (auto& h : hold_base_) h.setZero();
  target_.setZero();
  observed_cumulative_.setZero();
  hold_obs_.setZero();
  hold_len_ = 0;
  gscore_ = {0.0, 0.0};
  if (corrector_) corrector_->reset();
  have_command_ = false;
  last_command_.setZero();
  last_eff_scale_.setOnes();
  steps_since_reset_ = 0;
  map_valid_ = false;
}

void GrammarBelief::observe_gripper(double raw_gripper, double finger_delta) {
  if (!model_.has_gripper()) throw std::logic_error("grammar belief: the response model has no finger channel");
  for (int inv = 0; inv < 2; ++inv) {
    const double pred = inv == 0 ? raw_gripper : -raw_gripper;
    const double r = (finger_delta - model_.gripper_alpha * pred) / model_.gripper_sigma;
    gscore_[static_cast<std::size_t>(inv)] -= 0.5 * r * r;
  }
  map_valid_ = false;
}

double GrammarBelief::drive(int m, int j) const {
  const Mode& mode = modes()[static_cast<std::size_t>(m)];
  const auto lag = static_cast<std::size_t>(mode.lag);
  const double x = history_[lag][j];
  return mode.target == Target::kDelta ? x : x - history_[lag + 1][j];
}

void GrammarBelief::add_mode_cells(int m, const Pose6& obs, const Pose6& base, const std::array<double, kPoseDim>& sigma) {
  for (int i = 0; i < kPoseDim; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    const double a = model_.alpha[ii];
    const double inv = 1.0 / sigma[ii];
    double* cell = &S_[index(m, i, 0, 0, 0)];
    for (int j = 0; j < kPoseDim; ++j) {
      const double b = a * base[j];
      for (std::size_t sk = 0; sk < coef_.size(); ++sk) {
        const double r = (obs[i] - b * coef_[sk]) * inv;
        *cell++ -= 0.5 * r * r;
      }
    }
  }
}

void GrammarBelief::add_cells(const Pose6& obs, const std::array<Pose6, kModes>& base,
                              const std::array<double, kPoseDim>& sigma) {
  for (int m = 0; m < kModes; ++m) add_mode_cells(m, obs, base[static_cast<std::size_t>(m)], sigma);
}

void GrammarBelief::push_history(const Action& raw) {
  for (int d = kHistory - 1; d > 0; --d) history_[static_cast<std::size_t>(d)] = history_[static_cast<std::size_t>(d - 1)];
  history_[0] = raw.head<kPoseDim>();
}

void GrammarBelief::update_per_mode(const Action& raw, const std::array<Pose6, kModes>& observed) {
  if (corrector_ || reanchor_period_ > 0)
    throw std::logic_error("GrammarBelief::update_per_mode: a belief with a scale corrector or re-anchoring takes one observation per step");
  push_history(raw);
  have_command_ = false;
  ++steps_since_reset_;
  Pose6 base;
  for (int m = 0; m < kModes; ++m) {
    for (int j = 0; j < kPoseDim; ++j) base[j] = drive(m, j);
    add_mode_cells(m, observed[static_cast<std::size_t>(m)], base, model_.sigma);
  }
  map_valid_ = false;
}

void GrammarBelief::update(const Action& raw, const Pose6& observed, bool hold, bool window_close, bool corrector_active) {
  push_history(raw);
  // the scale corrector learns from the previous map_encode's command, before scoring (reference order)
  if (corrector_ && have_command_) corrector_->accumulate(last_command_, observed, last_eff_scale_, corrector_active);
  have_command_ = false;
  observed_cumulative_ += observed;
  ++steps_since_reset_;
  if (reanchor_period_ > 0 && steps_since_reset_ % reanchor_period_ == 0)
    target_.head<3>() = observed_cumulative_.head<3>();  // rotation channels keep the cumulative intent
  std::array<Pose6, kModes> base;
  for (int m = 0; m < kModes; ++m)
    for (int j = 0; j < kPoseDim; ++j) base[static_cast<std::size_t>(m)][j] = drive(m, j);
  if (hold) {
    hold_obs_ += observed;
    for (int m = 0; m < kModes; ++m) hold_base_[static_cast<std::size_t>(m)] += base[static_cast<std::size_t>(m)];
    ++hold_len_;
    if (window_close) {
      std::array<double, kPoseDim> sigma_eff{};
      const double f = std::sqrt(static_cast<double>(std::max(hold_len_, 1)));
      for (std::size_t c = 0; c < sigma_eff.size(); ++c) sigma_eff[c] = model_.sigma[c] * f;
      add_cells(hold_obs_, hold_base_, sigma_eff);
      hold_obs_.setZero();
      for (auto& h : hold_base_) h.setZero();
      hold_len_ = 0;
    }
  } else {
    add_cells(observed, base, model_.sigma);
  }
  map_valid_ = false;
}

const GrammarBelief::Map& GrammarBelief::map() const {
  if (map_valid_) return map_;
  constexpr int kN = kPoseDim;
  constexpr int kMasks = 1 << kN;
  double best_total = -std::numeric_limits<double>::infinity();
  ContractFields chosen;
  int chosen_mode = 0;
  for (int m = 0; m < kModes; ++m) {
    // best (sign, scale) per cell: the first maximum of the flattened s·7 + k
    std::array<std::array<double, kN>, kN> best{};
    std::array<std::array<int, kN>, kN> arg{};
    for (int i = 0; i < kN; ++i)
      for (int j = 0; j < kN; ++j) {
        const double* cell = &S_[index(m, i, j, 0, 0)];
        int a = 0;
        for (int sk = 1; sk < kSigns * kScales; ++sk)
          if (cell[sk] > cell[a]) a = sk;
        best[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = cell[a];
        arg[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = a;
      }
    // the best assignment (row i = output channel, column j = raw channel) by dynamic programming
    // over the set of used columns; the first column attaining the maximum wins, so equal costs
    // give the identity (as the reference's linear_sum_assignment does)
    std::array<double, kMasks> g{};
    std::array<int, kMasks> choice{};
    for (int mask = kMasks - 1; mask >= 0; --mask) {
      const int row = __builtin_popcount(static_cast<unsigned>(mask));
      if (row == kN) {
        g[static_cast<std::size_t>(mask)] = 0.0;
        continue;
      }
      double v = -std::numeric_limits<double>::infinity();
      int c = -1;
      for (int j = 0; j < kN; ++j) {
        if (mask & (1 << j)) continue;
        const double x = best[static_cast<std::size_t>(row)][static_cast<std::size_t>(j)] + g[static_cast<std::size_t>(mask | (1 << j))];
        if (c < 0 || x > v) {
          v = x;
          c = j;
        }
      }
      g[static_cast<std::size_t>(mask)] = v;
      choice[static_cast<std::size_t>(mask)] = c;
    }
    const double total = g[0];
    if (m == 0 || total > best_total) {
      best_total = total;
      chosen_mode = m;
      ContractFields f;
      int mask = 0;
      for (int i = 0; i < kN; ++i) {
        const int j = choice[static_cast<std::size_t>(mask)];
        mask |= 1 << j;
        const int sk = arg[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
        f.permutation[static_cast<std::size_t>(i)] = j;
        f.sign[static_cast<std::size_t>(i)] = sk / kScales == 0 ? -1 : 1;
        f.scale[static_cast<std::size_t>(i)] = grammar::kScaleGrid[static_cast<std::size_t>(sk % kScales)];
      }
      const Mode& mode = modes()[static_cast<std::size_t>(m)];
      f.target = to_string(mode.target);
      f.frame = "base";
      f.lag = mode.lag;
      f.gripper_inverted = gscore_[1] > gscore_[0];  // both 0 without a finger channel
      chosen = f;
    }
  }
  map_ = Map{Contract::make(chosen), chosen_mode, best_total};
  map_valid_ = true;
  return map_;
}

Action GrammarBelief::map_encode(const Action& canonical, bool accumulate) {
  Action raw;
  if (corrector_) {  // encode with the corrected scale and remember the command for the next update
    const Contract& c = map().contract;
    Pose6 base;
    for (int i = 0; i < kPoseDim; ++i) base[i] = c.scale()[static_cast<std::size_t>(i)];
    last_eff_scale_ = corrector_->effective_scale(base);
    last_command_ = canonical.head<kPoseDim>();
    have_command_ = true;
    if (last_eff_scale_ == base) {
      raw = actionshift::encode(c, canonical, Mat3::Identity(), target_);
    } else {
      ContractFields f = c.fields();
      for (int i = 0; i < kPoseDim; ++i) f.scale[static_cast<std::size_t>(i)] = last_eff_scale_[i];
      raw = actionshift::encode(Contract::make(f), canonical, Mat3::Identity(), target_);
    }
  } else {
    raw = actionshift::encode(map().contract, canonical, Mat3::Identity(), target_);
  }
  // a non-finite intent (which the env refuses) must not poison the tracked target for the rest of the episode
  if (accumulate && canonical.head<kPoseDim>().allFinite()) target_ += canonical.head<kPoseDim>();
  return raw;
}

Action GrammarBelief::probe_candidate(int index, double amplitude) {
  Action a = Action::Zero();
  a[index % kPoseDim] = index < kPoseDim ? amplitude : -amplitude;
  return a;
}

int GrammarBelief::select_entropy_probe(double amplitude) const {
  constexpr int kSK = kSigns * kScales;
  // per output channel i: the cell posterior's first two moments of sign·scale per (m, j)
  std::array<double, static_cast<std::size_t>(kPoseDim * kModes * kPoseDim)> w1{}, w2{};
  for (int i = 0; i < kPoseDim; ++i) {
    double top = -std::numeric_limits<double>::infinity();
    for (int m = 0; m < kModes; ++m) {
      const double* cell = &S_[index(m, i, 0, 0, 0)];
      for (int x = 0; x < kPoseDim * kSK; ++x) top = std::max(top, cell[x]);
    }
    double z = 0.0;
    for (int m = 0; m < kModes; ++m)
      for (int j = 0; j < kPoseDim; ++j) {
        const double* cell = &S_[index(m, i, j, 0, 0)];
        double a1 = 0.0, a2 = 0.0;
        for (int sk = 0; sk < kSK; ++sk) {
          const double w = std::exp(cell[sk] - top);
          const double c = coef_[static_cast<std::size_t>(sk)];
          z += w;
          a1 += w * c;
          a2 += w * c * c;
        }
        const auto at = static_cast<std::size_t>((i * kModes + m) * kPoseDim + j);
        w1[at] = a1;
        w2[at] = a2;
      }
    for (std::size_t at = static_cast<std::size_t>(i * kModes * kPoseDim); at < static_cast<std::size_t>((i + 1) * kModes * kPoseDim); ++at) {
      w1[at] /= z;
      w2[at] /= z;
    }
  }
  // the drive of every mode and raw channel if `pulse` were sent now: the history shifted by one
  auto drive_with = [&](int m, int j, double pulse_j) {
    const Mode& mode = modes()[static_cast<std::size_t>(m)];
    const auto lag = static_cast<std::size_t>(mode.lag);
    const double x = lag == 0 ? pulse_j : history_[lag - 1][j];
    if (mode.target == Target::kDelta) return x;
    return x - history_[lag][j];
  };
  int best = 0;
  double best_score = -std::numeric_limits<double>::infinity();
  for (int q = 0; q < 2 * kPoseDim; ++q) {
    const Action pulse = probe_candidate(q, amplitude);
    double score = 0.0;
    for (int i = 0; i < kPoseDim; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      double mean = 0.0, second = 0.0;
      for (int m = 0; m < kModes; ++m)
        for (int j = 0; j < kPoseDim; ++j) {
          const double d = drive_with(m, j, pulse[j]);
          const auto at = static_cast<std::size_t>((i * kModes + m) * kPoseDim + j);
          mean += d * w1[at];
          second += d * d * w2[at];
        }
      const double a = model_.alpha[ii];
      const double var = std::max(0.0, a * a * (second - mean * mean));
      score += 0.5 * std::log1p(var / (model_.sigma[ii] * model_.sigma[ii]));
    }
    if (q == 0 || score > best_score + 1e-12 * std::abs(best_score)) {  // first on ties (up to rounding)
      best = q;
      best_score = score;
    }
  }
  return best;
}

// ---- GrammarBeliefAdapter

GrammarBeliefAdapter::GrammarBeliefAdapter(const ResponseModel& model, GrammarOptions options)
    : belief_(model, options.scale, options.reanchor_period), options_(options) {
  if (options_.budget < 0) throw std::invalid_argument("probe budget must be nonnegative");
  if (!std::isfinite(options_.amplitude) || !(options_.amplitude > 0.0))
    throw std::invalid_argument("probe amplitude must be finite and positive");
  if (options_.gripper_channel && !model.has_gripper())
    throw std::invalid_argument("the calibration has no finger channel (run `actionshift calibrate --gripper-channel`)");
}

int GrammarBeliefAdapter::probe_steps() const noexcept {
  switch (options_.probe) {
    case GrammarProbe::kFixed:
    case GrammarProbe::kEntropy: return options_.budget;
    case GrammarProbe::kHold: return options_.hold.total_steps();
    case GrammarProbe::kNone: break;
  }
  return 0;
}

void GrammarBeliefAdapter::begin_episode(std::uint64_t) {
  belief_.reset();
  steps_ = 0;
  exec_step_ = 0;
  last_probe_ = false;
  have_fingers_ = false;
  last_ = {};
}

Action GrammarBeliefAdapter::encode(const Action& canonical, const Mat3&) {
  const int total = probe_steps();
  const bool probing = steps_ < total;
  Action raw;
  if (options_.probe == GrammarProbe::kHold) {
    if (steps_ == total) belief_.anchor_tracked_target();
    const Action task = belief_.map_encode(canonical, !probing);  // no intent accumulates while holding
    raw = probing ? options_.hold.action(steps_) : task;
  } else {
    const Action task = belief_.map_encode(canonical, true);  // computed every step, as the reference
    if (probing)
      raw = options_.probe == GrammarProbe::kEntropy ? GrammarBelief::probe_candidate(belief_.select_entropy_probe(options_.amplitude), options_.amplitude)
                                                     : fixed_probe_pulse(steps_, options_.amplitude);
    else
      raw = task;
  }
  if (!probing && !options_.belief_after_probe) raw = canonical;
  exec_step_ = steps_;
  ++steps_;
  last_probe_ = probing;
  last_.probe = probing;
  return raw;
}

void GrammarBeliefAdapter::observe_fingers(double finger_delta) {
  fingers_ = finger_delta;
  have_fingers_ = true;
}

void GrammarBeliefAdapter::observe(const Action& raw, const Pose6& response, const Mat3&) {
  if (options_.gripper_channel && have_fingers_) belief_.observe_gripper(raw[kGripper], fingers_);
  have_fingers_ = false;
  const bool hold = options_.probe == GrammarProbe::kHold && last_probe_;
  belief_.update(raw, response, hold, hold && options_.hold.is_window_close(exec_step_), !last_probe_);
}

}  // namespace actionshift::adapt
