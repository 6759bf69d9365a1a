// Joint logs without video, and robot-learning datasets, measured against baselines in the same run:
//   1. `kccd check` (kccd::overlay::runCheck: the log read, every sample queried on every core,
//      static collision query) on a 1 kHz log of the model (default: one hour, 3.6 M samples),
//      against the plain query loop over the same samples on one thread (a Checker, the same
//      query, the states taken from the parsed log) and against reading the log alone;
//   2. reading a LeRobot episode's state rows from Parquet (parquet-wasm's file, snappy pages:
//      kccd::logs::readLerobotRows) against parsing the same rows from a CSV state log.
// Usage: bench_dataset NODE WRITER_MJS [--model M] [--samples N] [--rows R] [--repeat K] [--dir D]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "bench/bench_recording.hpp"
#include "kccd/checker.hpp"
#include "kccd/logs/lerobot_dataset.hpp"
#include "kccd/overlay/jobs/check_job.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/state_log.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The baseline: one Checker, the same collision query, every sample of the parsed log in order.
std::size_t queryLoop(const kccd::Model& model, const kccd::StateLog& log) {
  kccd::Checker checker(model);
  std::size_t within = 0;
  const kccd::QueryOptions options{.type = kccd::QueryType::Collision, .tight_volumes = true};
  for (std::size_t i = 0; i < log.rows(); ++i) {
    const auto q = log.row(i);
    within += kccd::safetyStatus(checker.query(q, q, options)) != kccd::SafetyStatus::Clear;
  }
  return within;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: bench_dataset NODE WRITER_MJS [--model M] [--samples N] [--rows R] [--repeat K] [--dir D]\n";
    return 2;
  }
  const std::string node = argv[1], writer = argv[2];
  std::string model_path = std::string(KCCD_DATA_DIR) + "/humanoid.yaml";
  long samples = 3600000, rows = 200000;
  int repeat = 3;
  std::string dir = (fs::temp_directory_path() / "kccd_bench_dataset").string();
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--model") model_path = v;
    if (k == "--samples") samples = std::stol(v);
    if (k == "--rows") rows = std::stol(v);
    if (k == "--repeat") repeat = std::max(1, std::stoi(v));
    if (k == "--dir") dir = v;
  }
  try {
    fs::create_directories(dir);
    const kccd::Model model = kccd::loadModel(model_path);
    const std::string log_path = dir + "/log.csv", rows_path = dir + "/rows.csv", dataset = dir + "/dataset";
    kccd::bench::makeLog(log_path, model, static_cast<double>(samples - 2) / 1000.0, 1000);
    kccd::bench::makeLog(rows_path, model, static_cast<double>(rows - 2) / 1000.0, 1000);
    fs::remove_all(dataset);
    const std::string write = node + " " + writer + " " + dataset + " " + rows_path +
                              " - --no-camera --episodes 1 --version v2.1 --writer pw --row-group 20000 > /dev/null";
    if (std::system(write.c_str()) != 0) throw std::runtime_error("failed: " + write);

    double read = 1e300, loop = 1e300, check = 1e300, check1 = 1e300, csv_rows = 1e300, parquet_rows = 1e300;
    std::size_t n = 0, loop_within = 0, check_within = 0, parquet_n = 0, csv_n = 0;
    const kccd::overlay::CheckRequest request{.states = log_path, .query = "collision"};
    kccd::overlay::CheckRequest one = request;
    one.jobs = 1;
    for (int round = 0; round < repeat; ++round) {
      auto t0 = Clock::now();
      const kccd::StateLog log = kccd::loadStateLog(log_path, model);
      read = std::min(read, since(t0));
      n = log.rows();
      t0 = Clock::now();
      loop_within = queryLoop(model, log);
      loop = std::min(loop, since(t0));
      t0 = Clock::now();
      const kccd::overlay::CheckResult all = kccd::overlay::runCheck(request, model);
      check = std::min(check, since(t0));
      check_within = all.report.within_margin + all.report.colliding;
      t0 = Clock::now();
      kccd::overlay::runCheck(one, model);
      check1 = std::min(check1, since(t0));
      t0 = Clock::now();
      const kccd::logs::LerobotRows parquet =
          kccd::logs::readLerobotRows(kccd::logs::openLerobotDataset(dataset), 0, "observation.state");
      parquet_rows = std::min(parquet_rows, since(t0));
      parquet_n = parquet.rows();
      t0 = Clock::now();
      csv_n = kccd::loadStateLog(rows_path, model).rows();
      csv_rows = std::min(csv_rows, since(t0));
    }
    std::printf("bench_dataset: %s, %zu state values; best of %d rounds\n", model.name.c_str(),
                static_cast<std::size_t>(model.stateSize()), repeat);
    std::printf("| what | samples | seconds | samples/s | ratio |\n|---|---|---|---|---|\n");
    std::printf("| read the CSV log | %zu | %.3f | %.0f | |\n", n, read, n / read);
    std::printf("| query loop, one thread (baseline) | %zu | %.3f | %.0f | 1.00 |\n", n, loop, n / loop);
    std::printf("| kccd check, one job (read + query) | %zu | %.3f | %.0f | %.2f |\n", n, check1, n / check1,
                check1 / loop);
    std::printf("| kccd check, every core (read + query) | %zu | %.3f | %.0f | %.2f |\n", n, check, n / check,
                check / loop);
    std::printf("| CSV state rows (baseline) | %zu | %.3f | %.0f | 1.00 |\n", csv_n, csv_rows, csv_n / csv_rows);
    std::printf("| Parquet state rows (LeRobot episode) | %zu | %.3f | %.0f | %.2f |\n", parquet_n, parquet_rows,
                parquet_n / parquet_rows, parquet_rows / csv_rows);
    if (loop_within != check_within) {
      std::fprintf(stderr, "bench_dataset: the check found %zu samples within the margin, the loop %zu\n", check_within,
                   loop_within);
      return 1;
    }
    if (parquet_n != csv_n) {
      std::fprintf(stderr, "bench_dataset: %zu Parquet rows, %zu CSV rows\n", parquet_n, csv_n);
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_dataset: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
