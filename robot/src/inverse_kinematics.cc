#include "chasles/robot/inverse_kinematics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "chasles/robot/error.h"
#include "chasles/robot/lie_group.h"
#include "format.h"
#include "kinematics_internal.h"

namespace chasles {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// Largest joint step of one iteration [rad or m]: keeps Newton steps inside the region where
/// the linearisation means something (far from the target the raw step can be huge).
constexpr double kMaxStep = 0.6;
/// An attempt is abandoned when its error has not dropped by 10 % in this many iterations.
constexpr int kStallIterations = 8;
/// Iterations stop at this fraction of the tolerances, so the FK check has a margin.
constexpr double kConvergenceMargin = 0.5;

std::string Num(double x) { return FormatNumber(x); }
std::string Short(double x) { return robot_internal::FormatNumber(x, 2); }

/// Uniform in [0, 1) from the top 53 bits of one draw (same on every platform).
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

void RequirePositive(double x, const char* field) {
  if (!(x > 0.0)) ThrowInvalid(std::string("ik.") + field + " = " + Num(x) + " must be > 0");
  if (!std::isfinite(x)) ThrowInvalid(std::string("ik.") + field + " = " + Num(x) + " must be finite");
}
void RequireNonNegative(double x, const char* field) {
  if (!(x >= 0.0)) ThrowInvalid(std::string("ik.") + field + " = " + Num(x) + " must be >= 0");
  if (!std::isfinite(x)) ThrowInvalid(std::string("ik.") + field + " = " + Num(x) + " must be finite");
}

/// Per dof that moves the link: limits and whether the joint is continuous (wraps into [-π, π]).
struct ChainDof {
  int dof;
  double lower, upper;
  bool continuous;
};

inline double Wrap(double x) { return std::remainder(x, 2.0 * kPi); }

inline double Limit(const ChainDof& c, double x) {
  if (c.continuous) return Wrap(x);
  return std::min(std::max(x, c.lower), c.upper);
}

/// Distance between two configurations over the chain dofs: max-norm, continuous joints the
/// short way round.
double ChainDistance(const std::vector<ChainDof>& chain, const Eigen::VectorXd& a,
                     const Eigen::VectorXd& b) {
  double d = 0.0;
  for (const ChainDof& c : chain) {
    double diff = a[c.dof] - b[c.dof];
    if (c.continuous) diff = Wrap(diff);
    d = std::max(d, std::abs(diff));
  }
  return d;
}

/// Position and orientation error of the link at q against the target, by the model's FK.
void PoseErrors(const RobotModel& robot, const Eigen::VectorXd& q, int link,
                const Eigen::Isometry3d& target, std::vector<Eigen::Isometry3d>* poses,
                double* position_error, double* orientation_error) {
  robot.ForwardKinematics(q, poses);
  const Eigen::Isometry3d& T = (*poses)[link];
  *position_error = (T.translation() - target.translation()).norm();
  *orientation_error = LogSO3(T.linear().transpose() * target.linear()).norm();
}

}  // namespace

void IkRequest::Validate(const RobotModel& robot) const {
  if (link < 0 || link >= robot.num_links()) {
    ThrowInvalid("ik.link = " + std::to_string(link) + " is not a link of robot '" + robot.name() +
                 "' (" + std::to_string(robot.num_links()) + " links)");
  }
  const Eigen::Matrix4d& m = target.matrix();
  if (!m.allFinite()) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (!std::isfinite(m(r, c))) {
          ThrowInvalid("ik.target(" + std::to_string(r) + ", " + std::to_string(c) + ") = " +
                       Num(m(r, c)) + " must be finite");
        }
      }
    }
  }
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    ThrowInvalid("ik.target is not in SE(3): its last row must be (0, 0, 0, 1)");
  }
  const Eigen::Matrix3d R = target.linear();
  const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if (orthogonality > 1e-6) {
    ThrowInvalid("ik.target is not in SE(3): its rotation has ‖RᵀR − I‖ = " + Short(orthogonality) +
                 " (must be <= 1e-06)");
  }
  if (R.determinant() < 0.0) {
    ThrowInvalid("ik.target is not in SE(3): its rotation has determinant " +
                 Short(R.determinant()) + " (must be +1)");
  }
  RequirePositive(position_tolerance, "position_tolerance");
  RequirePositive(orientation_tolerance, "orientation_tolerance");
  RequireNonNegative(damping, "damping");
  if (max_iterations < 1) {
    ThrowInvalid("ik.max_iterations = " + std::to_string(max_iterations) + " must be >= 1");
  }
  if (max_solutions < 1) {
    ThrowInvalid("ik.max_solutions = " + std::to_string(max_solutions) + " must be >= 1");
  }
  RequireNonNegative(distinct_distance, "distinct_distance");
  RequirePositive(time_budget, "time_budget");
  if (max_attempts < 0) {
    ThrowInvalid("ik.max_attempts = " + std::to_string(max_attempts) + " must be >= 0 (0 = until the budget is spent)");
  }
  if (initial_guess.size() != 0) robot.ValidateConfiguration(initial_guess, "ik.initial_guess");
}

namespace {

/// The joint step dq that the chain's space Jacobian J maps onto the twist error Vs (error
/// norm e): Newton–Raphson with the pseudo-inverse J⁺ = Jᵀ (JJᵀ)⁺ (an LDLT solve when JJᵀ is well
/// conditioned, an eigen-decomposition pseudo-inverse otherwise), or with `dls` damped least
/// squares Jᵀ(JJᵀ + λ²I)⁻¹V, λ shrinking with the error so that the last steps are Newton steps
/// (quadratic convergence) while large errors stay damped.
/// A joint on a limit that the step would push further out is taken out of the step (its column
/// of *J zeroed) and the step solved again by the others, until no joint is pushed out: clamping
/// it instead would leave the rest of the step aimed at a motion that joint cannot make, and the
/// attempt stalls there. *J is left with those columns zeroed.
void JointStep(const std::vector<ChainDof>& chain, const Eigen::VectorXd& q, const Vector6d& Vs, double e, bool dls,
               double lambda2, Eigen::Matrix<double, 6, Eigen::Dynamic>* J, Eigen::VectorXd* dq) {
  const int k = static_cast<int>(chain.size());
  for (int pass = 0; pass <= k; ++pass) {
    Matrix6d G;
    G.noalias() = *J * J->transpose();
    Vector6d y;
    bool solved = false;
    if (!dls) {
      const Eigen::LDLT<Matrix6d> ldlt(G);
      const auto D = ldlt.vectorD();
      if (ldlt.info() == Eigen::Success && D.minCoeff() > 1e-10 * D.maxCoeff()) {
        y = ldlt.solve(Vs);
        solved = true;
      }
    }
    if (solved) {
      // done
    } else if (dls) {
      const double l2 = lambda2 * std::min(1.0, 10.0 * e) + 1e-12;
      G.diagonal().array() += l2;
      y = G.ldlt().solve(Vs);
    } else {
      const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(G);
      const Vector6d& ev = eig.eigenvalues();
      const double cutoff = std::max(ev[5], 1e-300) * 1e-10;
      const Vector6d coeff = eig.eigenvectors().transpose() * Vs;
      Vector6d scaled;
      for (int i = 0; i < 6; ++i) scaled[i] = ev[i] > cutoff ? coeff[i] / ev[i] : 0.0;
      y.noalias() = eig.eigenvectors() * scaled;
    }
    dq->noalias() = J->transpose() * y;
    bool blocked = false;
    for (int j = 0; j < k; ++j) {
      const ChainDof& c = chain[j];
      const double x = q[c.dof];
      if (!c.continuous && ((x <= c.lower && (*dq)[j] < 0.0) || (x >= c.upper && (*dq)[j] > 0.0)) &&
          !J->col(j).isZero()) {
        J->col(j).setZero();
        blocked = true;
      }
    }
    if (!blocked) return;
  }
}

}  // namespace

IkResult SolveIk(const RobotModel& robot, const IkRequest& request) {
  request.Validate(robot);
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const Clock::time_point deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(request.time_budget));

  const int link = request.link;
  const int n = robot.num_dofs();
  // The link's moving joints (PoE factors) and the distinct dofs that drive them, in chain
  // order: J's column of a dof sums multiplier × the columns of the joints it drives (a mimic
  // joint downstream of its actuated joint moves the link twice).
  const std::vector<int>& chain_joints = robot.link_chain(link);
  std::vector<int> column_of(chain_joints.size());  // chain joint -> column of J
  std::vector<double> multiplier_of(chain_joints.size());
  std::vector<ChainDof> chain;
  {
    std::vector<int> column_of_dof(n, -1);
    for (std::size_t j = 0; j < chain_joints.size(); ++j) {
      const Joint& joint = robot.joints()[robot.moving_joint(chain_joints[j])];
      const int d = joint.dof;
      if (column_of_dof[d] < 0) {
        column_of_dof[d] = static_cast<int>(chain.size());
        // A continuous joint wraps only while nothing narrowed its [-π, π] (a mimic joint can).
        const bool wraps = robot.joints()[robot.dof_joint(d)].type == JointType::kContinuous &&
                           robot.lower_limits()[d] == -kPi && robot.upper_limits()[d] == kPi;
        chain.push_back({d, robot.lower_limits()[d], robot.upper_limits()[d], wraps});
      }
      column_of[j] = column_of_dof[d];
      multiplier_of[j] = joint.multiplier();
    }
  }
  const int k = static_cast<int>(chain.size());

  const Eigen::Matrix3d R_target = request.target.linear();
  const Eigen::Vector3d p_target = request.target.translation();
  const double tol_p = request.position_tolerance;
  const double tol_o = request.orientation_tolerance;
  const double lambda2 = request.damping * request.damping;
  const bool dls = request.method == IkMethod::kDampedLeastSquares;

  // Dofs that do not move the link keep the initial guess (or 0 moved into the limits).
  Eigen::VectorXd base(n);
  for (int d = 0; d < n; ++d) {
    base[d] = request.initial_guess.size() == n
                  ? request.initial_guess[d]
                  : std::min(std::max(0.0, robot.lower_limits()[d]), robot.upper_limits()[d]);
  }

  std::mt19937_64 rng(request.seed);
  IkResult result;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, k);
  Eigen::VectorXd q(n), dq(k);
  std::vector<Eigen::Isometry3d> poses;
  double best_score = std::numeric_limits<double>::infinity();
  double best_p = std::numeric_limits<double>::infinity();
  double best_o = std::numeric_limits<double>::infinity();
  int rejected = 0;

  const auto consider_best = [&](double pe, double oe) {
    const double score = std::max(pe / tol_p, oe / tol_o);
    if (score < best_score) {
      best_score = score;
      best_p = pe;
      best_o = oe;
    }
  };

  for (;;) {
    // ---- Start of an attempt: the initial guess first, then uniform within the limits.
    q = base;
    if (result.attempts == 0 && request.initial_guess.size() == n) {
      // keep q = initial guess
    } else {
      for (const ChainDof& c : chain) q[c.dof] = c.lower + (c.upper - c.lower) * Uniform01(rng);
    }
    ++result.attempts;

    bool converged = false;
    double attempt_best = std::numeric_limits<double>::infinity();
    int stall = 0;
    bool dls_now = dls;
    double previous_error = std::numeric_limits<double>::infinity();
    for (int iteration = 0; iteration < request.max_iterations; ++iteration) {
      if ((iteration & 15) == 15 && (Clock::now() >= deadline || (request.stop && request.stop()))) break;
      Eigen::Matrix3d R;
      Eigen::Vector3d p;
      J.setZero();
      kinematics_internal::ChainForward(
          robot, q.data(), chain_joints, link, &R, &p,
          [&](int j, const Eigen::Vector3d& w, const Eigen::Vector3d& v) {
            const double mult = multiplier_of[j];
            J.col(column_of[j]).head<3>() += mult * w;
            J.col(column_of[j]).tail<3>() += mult * v;
          });
      // Body twist error V_b = log(T_sb⁻¹ T_target).
      Eigen::Isometry3d error;
      error.linear().noalias() = R.transpose() * R_target;
      error.translation().noalias() = R.transpose() * (p_target - p);
      error.makeAffine();
      const Vector6d Vb = LogSE3(error);
      const double pe = (p_target - p).norm();
      const double oe = Vb.head<3>().norm();
      consider_best(pe, oe);
      if (pe <= kConvergenceMargin * tol_p && oe <= kConvergenceMargin * tol_o) {
        converged = true;
        break;
      }
      // Early exit of hopeless attempts (stuck at a limit or in a local minimum).
      const double e = Vb.norm();
      if (e < 0.9 * attempt_best) {
        attempt_best = e;
        stall = 0;
      } else if (++stall >= kStallIterations) {
        break;
      }
      // Solve J_b Δq = V_b in the space frame: J_s Δq = [Ad_T] V_b (same Δq, no J_b needed).
      Vector6d Vs;
      Vs.head<3>().noalias() = R * Vb.head<3>();
      Vs.tail<3>().noalias() = R * Vb.tail<3>();
      Vs.tail<3>() += p.cross(Vs.head<3>());
      // Newton–Raphson falls back to damped steps for the rest of the attempt once a full
      // step has made the error grow (it overshot, typically near a singularity).
      if (!dls_now && e > previous_error) dls_now = true;
      previous_error = e;
      JointStep(chain, q, Vs, e, dls_now, lambda2, &J, &dq);
      const double largest = k > 0 ? dq.cwiseAbs().maxCoeff() : 0.0;
      if (!(largest <= kMaxStep)) {
        if (!std::isfinite(largest)) break;
        dq *= kMaxStep / largest;
      }
      for (int j = 0; j < k; ++j) q[chain[j].dof] = Limit(chain[j], q[chain[j].dof] + dq[j]);
    }

    if (converged) {
      // Verify by the model's own FK, the limits, distinctness and the caller's test.
      double pe, oe;
      PoseErrors(robot, q, link, request.target, &poses, &pe, &oe);
      bool valid = pe <= tol_p && oe <= tol_o;
      for (int d = 0; valid && d < n; ++d) {
        valid = q[d] >= robot.lower_limits()[d] && q[d] <= robot.upper_limits()[d];
      }
      for (const Eigen::VectorXd& s : result.solutions) {
        if (!valid) break;
        valid = ChainDistance(chain, q, s) >= request.distinct_distance;
      }
      if (valid && request.accept && !request.accept(q)) {
        valid = false;
        ++rejected;
      }
      if (valid) {
        if (result.solutions.empty()) {
          result.best_position_error = pe;
          result.best_orientation_error = oe;
        }
        result.solutions.push_back(q);
        if (static_cast<int>(result.solutions.size()) >= request.max_solutions) break;
      }
    }
    if (k == 0) break;  // nothing moves the link: every further attempt is the same
    if (request.max_attempts > 0 && result.attempts >= request.max_attempts) break;
    if (Clock::now() >= deadline || (request.stop && request.stop())) break;
  }

  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const int found = static_cast<int>(result.solutions.size());
  const std::string budget = "within " + Num(request.time_budget) + " s (" +
                             std::to_string(result.attempts) + " attempts)";
  const std::string rejected_note =
      rejected > 0 ? std::to_string(rejected) + " candidates within tolerance were rejected by accept"
                   : std::string();
  if (found >= request.max_solutions) {
    result.status = IkStatus::kSuccess;
  } else if (found > 0) {
    result.status = IkStatus::kPartial;
    result.message = "found " + std::to_string(found) + " of " +
                     std::to_string(request.max_solutions) + " distinct solutions " + budget +
                     (rejected > 0 ? "; " + rejected_note : std::string());
  } else {
    result.status = IkStatus::kNoSolution;
    result.best_position_error = best_p;
    result.best_orientation_error = best_o;
    std::string reason;
    if (rejected > 0) {
      reason = rejected_note;
    } else if (best_p > 100.0 * tol_p || best_o > 100.0 * tol_o) {
      reason = "the target is probably out of reach";
    } else {
      reason = "the target is at the edge of the workspace or of the joint limits; a larger "
               "time_budget or tolerance may help";
    }
    result.message = "no solution " + budget + ": best position error " + Short(best_p) +
                     " m, orientation error " + Short(best_o) + " rad — " + reason;
  }
  return result;
}

}  // namespace chasles
