// A program outside the project that uses the installed library.
#include <cmath>
#include <cstdio>
#include <vector>

#include <kccd/distance.hpp>

int main() {
  const std::vector<kccd::Vec3> a{{0, 0, 0}, {1, 0, 0}};
  const std::vector<kccd::Vec3> b{{0, 3, 0}, {1, 3, 0}};
  const double d = kccd::distance({a, 0.5}, {b, 0.5}).distance;
  std::printf("distance %.6f\n", d);
  return std::abs(d - 2.0) < 1e-9 ? 0 : 1;
}
