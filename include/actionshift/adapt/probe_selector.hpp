#pragma once
/// \file The allocation-free workspace behind entropy probing and DualABI (methods.hpp).
///
/// A selection scores every probe candidate by simulating, for each active hypothesis h, the
/// observation h predicts and the posterior the belief would move to. The work shared across
/// candidates and hypotheses is done once:
/// - the active set (largest mass first) and its probabilities, once per step;
/// - per candidate, each active hypothesis' prediction once, scaled by α/σ, so that the squared
///   Mahalanobis distance between two hypotheses' observations is one symmetric n × n matrix
///   (the log-likelihood of "h observed, j explains it" is −½ D(j, h));
/// - all n posteriors of a candidate as one n × n array, laid out so that hypothesis h's posterior
///   is lane h of every row: the column maxima, sums and entropy terms are then vertical vector
///   operations (no horizontal reductions, each sum taken in row order whatever the vector width),
///   computed by a kernel compiled for AVX2 and for baseline x86-64 (the same operations per lane,
///   no fused multiply-add, so both give the same bits) with its own vectorised exp (the Cephes
///   rational approximation Eigen uses, equal to Eigen's `exp` on [−708, 0] and exactly 0 below −708,
///   where exp < 2⁻¹⁰²¹ cannot move a sum whose largest term is 1);
/// - DualABI's pairwise task error E once per step, with each hypothesis' encoding of the recent
///   window computed once and the other hypotheses' decoding done on the whole window at a time
///   (the tool-frame rotation is moved to the intents' side, where ‖R v‖ = ‖v‖ removes it), and its
///   regret columns (each posterior's MAP and the expected task error of acting on it) in the same
///   lane layout.
/// Every buffer is sized at construction for the pool and `max_active`; a selection allocates
/// nothing.

#include "actionshift/adapt/pool_belief.hpp"
#include "actionshift/core/types.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace actionshift::adapt {

/// The active set of a belief with probabilities `p`: the largest-mass hypotheses (ties by index)
/// until `mass` is covered or `max_active` are taken, written to `out` in increasing index order;
/// returns how many. `order` is scratch of p.size(); `out` holds min(max(1, max_active), p.size()).
int active_set(const Eigen::Ref<const Eigen::VectorXd>& p, int max_active, double mass, std::span<int> order,
               std::span<int> out);

class ProbeSelector {
 public:
  /// `pool_size` hypotheses, at most `max_active` of them active, a DualABI window of `window`
  /// intents (0 if task errors are never computed). Throws std::invalid_argument on sizes < 1.
  ProbeSelector(int pool_size, int max_active, int window = 0);

  /// The active set of `b` (active_hypotheses() of methods.hpp), its probabilities and mass.
  void select_active(const PoolBelief& b, int max_active, double mass);
  /// An explicit active set (indices into the pool, each once).
  void set_active(const PoolBelief& b, std::span<const int> active);

  int num_active() const noexcept { return n_; }
  std::span<const int> active() const noexcept { return {active_.data(), static_cast<std::size_t>(n_)}; }
  /// Σ p over the active hypotheses, summed in increasing index order.
  double active_mass() const noexcept { return mass_; }

  /// Expected posterior entropy of observing the response to `candidate` (weights p_h / mass) and,
  /// if `motion` is non-null, the belief-weighted expected response magnitude Σ p_h/mass ‖α ⊙ pred_h‖.
  double expected_entropy(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                          bool lag_aware, double* motion = nullptr);

  /// The posteriors behind the last expected_entropy / expected_future_regret call: column h is the
  /// belief over the active set after observing the response h predicts (n × n; allocates, for tests).
  Eigen::MatrixXd last_posteriors() const;

  /// DualABI: the pairwise task error E(i, j) over the active set for the window `recent`
  /// (‖decode_j(encode_i(a)) − a‖ averaged over the window, 0 on the diagonal).
  void compute_task_error(const PoolBelief& b, std::span<const Action> recent, const Mat3& R);
  /// Load an explicit task-error matrix (n × n over the active set).
  void set_task_error(const Eigen::MatrixXd& E);
  /// Copy of the current task-error matrix.
  Eigen::MatrixXd task_error() const;
  /// Regret of acting on the MAP of the active set's normalised probabilities.
  double current_regret();
  /// Expected regret after observing the response to `candidate` (weights p_h / Σ p). Both regrets
  /// need a task error (a selector built with window ≥ 1); otherwise std::logic_error.
  double expected_future_regret(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated,
                                bool lag_aware);

 private:
  // predictions of the active hypotheses for one candidate, one channel per row of ld_ lanes (lane
  // j: hypothesis j): S = α/σ ⊙ pred (model side), O = the simulated observation / σ (equal to S
  // under the calibrated preview); motion_ = ‖α ⊙ pred‖
  void predict(const PoolBelief& b, const Action& candidate, const Mat3& R, bool calibrated, bool lag_aware, bool motion);
  // the n × n posterior numerators E(j, h) = exp(log p_j − ½ D(j, h) − max_h) (row j, lane h: h
  // observed), with per-lane max_, sums_ and weighted_ = Σ_j E·(log-numerator − max)
  void posteriors(bool calibrated);

  int pool_size_, max_active_, window_;
  int ld_;  // lanes per row: max_active rounded up to a multiple of 4
  int n_{0};
  double mass_{0};
  std::vector<int> order_;   // pool_size, scratch for the active set
  std::vector<int> active_;  // max_active
  Eigen::VectorXd p_all_;    // pool_size
  Eigen::VectorXd p_;        // active probabilities
  std::vector<double> logp_;  // active log-probabilities (ld_)
  std::vector<double> S_, O_;  // kPoseDim rows × ld_
  Eigen::VectorXd motion_;   // ‖α ⊙ pred‖ per active hypothesis
  std::vector<double> buf_;  // n × ld_ work array (log-numerators, then their exp)
  std::vector<double> max_, sums_, weighted_, regret_;  // ld_ lanes
  Eigen::VectorXd post_;
  // DualABI
  std::vector<double> q_;  // n × ld_ normalised posteriors (regret columns)
  Eigen::MatrixXd Et_;  // transposed task error: Et_(j, i) = E(i, j), so a row of E is a column
  int ldw_{0};               // lanes per window row: window rounded up to a multiple of 4
  std::vector<double> raw_;  // one hypothesis' encoded window, kPoseDim rows × ldw_
  std::vector<double> Y_;    // each hypothesis' targets for the window, kPoseDim·n rows × ldw_
  std::vector<double> sq_;   // squared decode errors of one hypothesis' encoding, n rows × ldw_
  std::vector<double> gain_;  // kPoseDim per active hypothesis
  std::vector<int> perm_;     // kPoseDim per active hypothesis
};

}  // namespace actionshift::adapt
