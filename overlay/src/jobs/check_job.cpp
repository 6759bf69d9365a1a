#include "kccd/overlay/jobs/check_job.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include "kccd/checker.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {
namespace {

InputError fieldError(const FieldSpelling& spell, const std::string& field, const std::string& problem) {
  return requestFieldError(spelledField(spell, field), problem);
}

// The most samples one check queries (a 1 kHz log of about 28 hours).
constexpr double kMaxSamples = 1e8;

// The log, read as the request says, and its warnings.
StateLog readLog(const CheckRequest& r, const Model& model, const FieldSpelling& spell,
                 std::vector<std::string>& warnings) {
  const JointMap map = r.joint_map.empty() ? JointMap{} : loadJointMap(r.joint_map, model);
  if (!r.bag.empty()) {
    BagRecording bag = readBagRecording({.bag = r.bag,
                                         .joint_topic = r.joint_topic,
                                         .time_source = *timeSourceOf(r.time_source),
                                         .joint_map = map,
                                         .spell = spell,
                                         .frames = false},
                                        model);
    warnings = bag.warnings;
    return std::move(bag.log);
  }
  if (!r.lerobot.empty()) {
    LerobotRecording episode = readLerobotRecording({.dataset = r.lerobot,
                                                     .episode = r.episode,
                                                     .state_key = r.state_key,
                                                     .joint_map = map,
                                                     .frames = false,
                                                     .spell = spell},
                                                    model);
    warnings = episode.warnings;
    return std::move(episode.log);
  }
  return loadStateLog(r.states, model, r.ignore_columns);
}

// One thread's share of the samples: its own checker and buffers, nothing shared but the output.
struct Worker {
  const Model& model;
  const StateLog& log;
  const CheckRequest& request;
  double max_gap;
  std::vector<BrakingParams> braking;
  bool keep;  // records kept for a report or timeline (else only the counts)

  void run(std::span<const double> times, std::span<FrameRecord> out, OverlayReport& counts,
           std::atomic<std::size_t>& done) const {
    Checker checker(model);
    const std::size_t n = static_cast<std::size_t>(model.stateSize());
    std::vector<double> q(n), v(n), lo(n), hi(n);
    const bool distances = request.query != "collision";
    const QueryOptions options{.type = distances ? QueryType::Distances : QueryType::Collision, .tight_volumes = true};
    FrameRecord scratch;
    for (std::size_t i = 0; i < times.size(); ++i) {
      FrameRecord& rec = keep ? out[i] : scratch;
      rec = FrameRecord{};
      rec.time = times[i];
      rec.match = request.swept ? stateAt(log, rec.time, max_gap, q, v) : stateAt(log, rec.time, max_gap, q);
      if (rec.match == StateMatch::None) {
        rec.status = SafetyStatus::NoState;
      } else {
        bool box_ok = true;
        if (request.swept) box_ok = brakingIntervals(model, q, v, braking, lo, hi);
        // As the overlay's view queries: from scratch for the distances (the same bound at the same
        // state, whichever thread had the sample before); warm from the last sample for a collision check.
        if (distances) checker.reset();
        const QueryResult& r = request.swept && box_ok ? checker.query(lo, hi, options) : checker.query(q, q, options);
        rec.braking_failed = !box_ok;
        if (keep) rec.values.assign(q.begin(), q.end());
        recordAnswer(model, r, box_ok, rec, keep);
      }
      counts.count(rec);
      if ((i & 1023) == 1023) done += 1024;
    }
  }
};

}  // namespace

void checkCheckRequest(const CheckRequest& r, const FieldSpelling& spell) {
  const auto named = [&](const std::string& f) { return spelledField(spell, f); };
  const int given = !r.states.empty() + !r.bag.empty() + !r.lerobot.empty();
  if (given != 1)
    throw InputError("give one of " + named("states") + " (a CSV state log), " + named("bag") + " (a robot log) or " +
                     named("lerobot") + " (a LeRobot dataset, with " + named("episode") + ")");
  if (!r.ignore_columns.empty() && r.states.empty())
    throw fieldError(spell, "ignore_columns", "goes with " + named("states"));
  if (r.bag.empty())
    for (const auto& [value, field] : {std::pair{&r.joint_topic, "joint_topic"}})
      if (!value->empty()) throw fieldError(spell, field, "goes with " + named("bag"));
  if (r.time_source != "header" && r.bag.empty()) throw fieldError(spell, "time_source", "goes with " + named("bag"));
  if (!timeSourceOf(r.time_source))
    throw fieldError(spell, "time_source", "expected 'header' or 'log', got '" + printable(r.time_source) + "'");
  if (!r.joint_map.empty() && r.bag.empty() && r.lerobot.empty())
    throw fieldError(spell, "joint_map", "goes with " + named("bag") + " or " + named("lerobot"));
  if (r.lerobot.empty()) {
    if (r.episode != -1) throw fieldError(spell, "episode", "goes with " + named("lerobot"));
    if (r.state_key != "observation.state") throw fieldError(spell, "state_key", "goes with " + named("lerobot"));
  } else if (r.episode < 0) {
    throw fieldError(spell, "episode", r.episode == -1 ? "give the episode (its episode_index)" : "must be >= 0");
  }
  const auto range = [&](double value, double lo, double hi, const std::string& field) {
    if (const std::optional<std::string> wrong = rangeProblem(value, lo, hi)) throw fieldError(spell, field, *wrong);
  };
  if (r.rate != 0.0) range(r.rate, 1e-6, 1e6, "rate");
  range(r.max_gap, 0, 1e300, "max_gap");
  if (r.query != "distances" && r.query != "collision")
    throw fieldError(spell, "query", "expected 'distances' or 'collision', got '" + printable(r.query) + "'");
  if (r.braking) {
    if (!r.swept) throw fieldError(spell, "braking", "only with " + named("swept") + " (static volumes do not brake)");
    if (const auto wrong = brakingRangeProblem(*r.braking))
      throw fieldError(spell, "braking." + wrong->first, wrong->second);
  }
  range(r.jobs, 0, 256, "jobs");
}

CheckResult runCheck(const CheckRequest& r, const Model& model, const FieldSpelling& spell,
                     const std::function<void(std::size_t, std::size_t)>& progress) {
  checkCheckRequest(r, spell);
  const OverlayOutputs outputs{.report = r.report,
                               .report_option = spelledField(spell, "report"),
                               .timeline = r.timeline,
                               .timeline_option = spelledField(spell, "timeline"),
                               .timeline_title = std::filesystem::path(!r.bag.empty()       ? r.bag
                                                                       : !r.lerobot.empty() ? r.lerobot
                                                                                            : r.states)
                                                     .filename()
                                                     .string() +
                                                 (r.lerobot.empty() ? "" : " episode " + std::to_string(r.episode))};
  checkOverlayOutputs(outputs, std::vector<std::string>{r.states, r.bag, r.lerobot, r.joint_map, r.model_file});
  CheckResult result;
  result.query = r.query;
  const StateLog log = readLog(r, model, spell, result.warnings);
  OverlayReport& report = result.report;
  report.margin = model.safety_margin;
  report.swept = r.swept;
  report.max_gap = r.max_gap > 0.0 ? r.max_gap : 1.5 * log.medianPeriod();

  std::vector<double> times;
  if (r.rate > 0.0) {
    const double span = log.times.back() - log.times.front();
    const double count = std::floor(span * r.rate + 1e-9) + 1;
    if (count > kMaxSamples)
      throw fieldError(spell, "rate", "would query " + messageNumber(count) + " samples (at most 1e8)");
    times.resize(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < times.size(); ++i) times[i] = log.times.front() + static_cast<double>(i) / r.rate;
  } else {
    times = log.times;
  }
  const bool keep = !r.report.empty() || !r.timeline.empty();
  if (keep) report.frames.resize(times.size());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t jobs = std::clamp<std::size_t>(r.jobs > 0 ? static_cast<std::size_t>(r.jobs) : cores, 1,
                                                   std::max<std::size_t>(1, times.size() / 256));
  report.jobs = static_cast<int>(jobs);
  const Worker worker{
      model,
      log,
      r,
      report.max_gap,
      std::vector<BrakingParams>(static_cast<std::size_t>(model.stateSize()), r.braking.value_or(kOverlayBraking)),
      keep};
  std::vector<OverlayReport> counts(jobs);
  std::vector<std::exception_ptr> errors(jobs);
  std::atomic<std::size_t> done{0};
  std::mutex mu;  // guards running
  std::condition_variable finished;
  std::size_t running = jobs;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> threads;
  for (std::size_t j = 0; j < jobs; ++j) {
    const std::size_t first = times.size() * j / jobs, end = times.size() * (j + 1) / jobs;
    threads.emplace_back([&, j, first, end] {
      try {
        worker.run(std::span(times).subspan(first, end - first),
                   keep ? std::span(report.frames).subspan(first, end - first) : std::span<FrameRecord>(), counts[j],
                   done);
      } catch (...) {
        errors[j] = std::current_exception();
      }
      const std::lock_guard lock(mu);
      if (--running == 0) finished.notify_all();
    });
  }
  {
    // Progress every 0.1 s while the workers run; a short log returns as soon as they are done.
    std::unique_lock lock(mu);
    while (!finished.wait_for(lock, std::chrono::milliseconds(100), [&] { return running == 0; }))
      if (progress) {
        lock.unlock();
        progress(std::min(done.load(), times.size()), times.size());
        lock.lock();
      }
  }
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  if (progress) progress(times.size(), times.size());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const OverlayReport& c : counts) {
    report.no_state += c.no_state;
    report.colliding += c.colliding;
    report.within_margin += c.within_margin;
    report.clear += c.clear;
    report.unsafe += c.unsafe;
  }
  VideoSink none({});
  if (keep) {
    result.json = writeOverlayOutputs(outputs, report, model, none);
  } else {
    result.json = reportJson(report, model, false);
  }
  result.json["samples"] = times.size();
  result.json["query"] = r.query;
  return result;
}

}  // namespace kccd::overlay
