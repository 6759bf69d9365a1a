#include "reference_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace kccd::testing {
namespace {

using LVec = Eigen::Matrix<long double, 3, 1>;
using LMat = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using LVecX = Eigen::Matrix<long double, Eigen::Dynamic, 1>;

// Affine minimiser of |sum alpha_i q_i| with sum alpha_i = 1: with D = [q_1 - q_0, ...] the
// least-squares solution of D mu = -q_0 (column-pivoting QR, which does not square the condition
// number the way the normal equations would: thin corrals far from the origin stay accurate).
LVecX affineMinimizer(const std::vector<LVec>& s) {
  const int n = static_cast<int>(s.size());
  LVecX alpha(n);
  if (n == 1) {
    alpha(0) = 1.0L;
    return alpha;
  }
  LMat d(3, n - 1);
  for (int i = 1; i < n; ++i) d.col(i - 1) = s[i] - s[0];
  const LVecX rhs = -s[0];
  const LVecX mu = d.colPivHouseholderQr().solve(rhs);
  alpha(0) = 1.0L - mu.sum();
  alpha.tail(n - 1) = mu;
  return alpha;
}

// Wolfe (1976): minimum-norm point of conv(q).
long double minNorm(const std::vector<LVec>& q) {
  long double scale2 = 0.0L;
  for (const LVec& p : q) scale2 = std::max(scale2, p.squaredNorm());
  const long double tol = 1e-17L * scale2;
  std::size_t first = 0;
  for (std::size_t i = 1; i < q.size(); ++i)
    if (q[i].squaredNorm() < q[first].squaredNorm()) first = i;
  std::vector<LVec> s{q[first]};
  std::vector<long double> lam{1.0L};
  LVec x = q[first];
  for (int major = 0; major < 1000; ++major) {
    if (x.squaredNorm() <= tol) return 0.0L;
    std::size_t j = 0;
    long double best = std::numeric_limits<long double>::infinity();
    for (std::size_t i = 0; i < q.size(); ++i) {
      const long double d = x.dot(q[i]);
      if (d < best) {
        best = d;
        j = i;
      }
    }
    if (x.squaredNorm() - best <= 1e-14L * x.squaredNorm() + 1e-24L * scale2) break;
    if (s.size() == 4) return 0.0L;  // a full-dimensional corral contains the origin
    s.push_back(q[j]);
    lam.push_back(0.0L);
    const long double before = x.squaredNorm();
    for (int minor = 0; minor < 100; ++minor) {
      const LVecX alpha = affineMinimizer(s);
      bool positive = true;
      for (int i = 0; i < alpha.size(); ++i) positive &= alpha(i) > 0.0L;
      if (positive) {
        for (int i = 0; i < alpha.size(); ++i) lam[i] = alpha(i);
        break;
      }
      // Step from lam towards alpha until the first weight hits zero; drop that point.
      long double theta = 1.0L;
      int leaving = -1;
      for (int i = 0; i < alpha.size(); ++i) {
        if (alpha(i) <= 0.0L) {
          const long double t = lam[i] - alpha(i) > 0.0L ? lam[i] / (lam[i] - alpha(i)) : 0.0L;
          if (leaving < 0 || t < theta) {
            theta = t;
            leaving = i;
          }
        }
      }
      for (int i = 0; i < alpha.size(); ++i) lam[i] = theta * alpha(i) + (1.0L - theta) * lam[i];
      lam[leaving] = 0.0L;
      std::vector<LVec> s2;
      std::vector<long double> lam2;
      for (std::size_t i = 0; i < s.size(); ++i) {
        if (lam[i] > 0.0L) {
          s2.push_back(s[i]);
          lam2.push_back(lam[i]);
        }
      }
      s.swap(s2);
      lam.swap(lam2);
    }
    long double sum = 0.0L;
    for (long double l : lam) sum += l;
    x.setZero();
    for (std::size_t i = 0; i < s.size(); ++i) x += (lam[i] / sum) * s[i];
    if (!(x.squaredNorm() < before)) break;  // rounding: the new point brought no descent
  }
  return x.norm();
}

LVec toL(const Eigen::Vector3d& p) { return p.cast<long double>(); }

}  // namespace

long double referenceHullDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  std::vector<LVec> diff;
  diff.reserve(a.size() * b.size());
  for (const auto& p : a)
    for (const auto& q : b) diff.push_back(toL(p) - toL(q));
  return minNorm(diff);
}

long double referenceSschDistance(const std::vector<Eigen::Vector3d>& a, double ra,
                                  const std::vector<Eigen::Vector3d>& b, double rb) {
  return std::max(0.0L, referenceHullDistance(a, b) - static_cast<long double>(ra) - static_cast<long double>(rb));
}

long double referencePointHullDistance(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& pts) {
  return referenceHullDistance({p}, pts);
}

}  // namespace kccd::testing
