// The C++ baseline of the Python package's benchmark (tests/bench/bench_python.py): the same
// loop query_many runs, over boxes read from a CSV file (each row: the lower ends, then the upper
// ends, in state order), a fresh table per box (Checker::reset), as query_many(reuse=False) does.
// Usage: bench_query_loop MODEL BOXES.csv TYPE REPEATS; prints the fastest run's µs per box.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "kccd/checker.hpp"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: bench_query_loop MODEL BOXES.csv collision|distances REPEATS\n";
    return 2;
  }
  const kccd::Model model = kccd::loadModel(argv[1]);
  const auto n = static_cast<std::size_t>(model.stateSize());
  std::vector<double> values;
  std::ifstream in(argv[2]);
  for (std::string line; std::getline(in, line);) {
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) values.push_back(std::stod(cell));
  }
  const std::size_t boxes = values.size() / (2 * n);
  if (boxes == 0 || values.size() != boxes * 2 * n) {
    std::cerr << argv[2] << ": expected rows of " << 2 * n << " numbers\n";
    return 2;
  }
  kccd::QueryOptions o;
  o.type = std::string(argv[3]) == "distances" ? kccd::QueryType::Distances : kccd::QueryType::Collision;
  kccd::Checker checker(model);
  double best = 1e300, sink = 0.0;
  for (int r = 0; r < std::stoi(argv[4]); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t b = 0; b < boxes; ++b) {
      checker.reset();
      const double* row = values.data() + b * 2 * n;
      sink += checker.query({row, n}, {row + n, n}, o).min_distance;
    }
    best = std::min(best, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::printf("%.4f\n", best / static_cast<double>(boxes));
  return sink == -1.0 ? 1 : 0;  // keeps the answers alive
}
