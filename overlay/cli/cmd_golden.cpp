// `kccd golden run | update | approve | list`: golden-image regression over a manifest in the
// integrator's repository (docs/formats.md section 9). The work is in the library
// (golden_manifest, golden_render, golden_check, golden_report); this file reads options and prints.
#include <fnmatch.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <set>

#include <nlohmann/json.hpp>

#include "cli_args.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/file_reader.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/golden/golden_check.hpp"
#include "kccd/overlay/golden/golden_manifest.hpp"
#include "kccd/overlay/golden/golden_render.hpp"
#include "kccd/overlay/golden/golden_report.hpp"
#include "kccd/render/gl_context.hpp"

namespace kccd::cli {
namespace {

namespace fs = std::filesystem;
using namespace kccd::overlay;

struct GoldenArgs {
  std::string manifest, out = "golden-results", only = "failed", from;
  std::vector<std::string> cases;  // globs
  bool keep_passing = false, quiet = false;
};

// The cases `globs` select (all without any); a glob that selects nothing is a mistake.
std::vector<std::size_t> selected(const GoldenManifest& m, const std::vector<std::string>& globs) {
  std::vector<std::size_t> out;
  std::set<std::string> used;
  for (std::size_t i = 0; i < m.cases.size(); ++i) {
    bool take = globs.empty();
    for (const std::string& g : globs)
      if (fnmatch(g.c_str(), m.cases[i].id.c_str(), 0) == 0) take = true, used.insert(g);
    if (take) out.push_back(i);
  }
  for (const std::string& g : globs)
    if (!used.count(g)) throw UsageError("--case " + g + ": no case of " + m.path + " matches");
  return out;
}

std::string outputsText(const CaseResult& r) {
  std::string s;
  for (const OutputResult& o : r.outputs)
    if (o.status != GoldenStatus::Passed)
      s += std::string(s.empty() ? "" : "; ") + goldenOutputName(o.output) + " " + goldenStatusName(o.status) + ": " +
           o.reason;
  return s;
}

// Renders and checks the selected cases, printing progress; the GL context's failure is exit 3.
GoldenRun check(const GoldenManifest& m, const std::vector<std::size_t>& cases, bool quiet) {
  GoldenRenderer renderer(m);  // every input read first: a mistake stops the run before any rendering
  GoldenRun run;
  run.manifest = &m;
  run.cases = cases;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const GoldenCase& c = m.cases[cases[k]];
    GoldenRendering r = renderer.render(cases[k]);
    CaseResult result = checkCase(c, r, goldenFolder(m, c.id));
    if (!quiet) {
      std::cerr << "[" << k + 1 << "/" << cases.size() << "] " << c.id << ": "
                << (result.passed()          ? "passed"
                    : !result.unsafe.empty() ? "unsafe query status " + result.unsafe
                                             : outputsText(result))
                << "\n";
    }
    run.renderings.push_back(std::move(r));
    run.results.push_back(std::move(result));
  }
  run.renderer = renderer.rendererString();
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return run;
}

Exit runRun(const GoldenArgs& a) {
  const GoldenManifest m = loadGoldenManifest(a.manifest);
  const std::vector<std::size_t> cases = selected(m, a.cases);
  const GoldenRun run = check(m, cases, a.quiet);
  writeGoldenReports(run, a.out, a.keep_passing);
  bool unsafe = false, failed = false;
  for (const CaseResult& r : run.results) {
    unsafe |= !r.unsafe.empty();
    failed |= !r.passed();
    if (!r.passed())
      std::cout << r.id << ": "
                << (r.unsafe.empty() ? outputsText(r) : "the query's status is " + r.unsafe + " (unsafe)")
                << (r.cause.empty() ? "" : " -- likely cause: " + r.cause) << "\n";
  }
  std::cout << goldenSummaryLine(run) << "; report " << (fs::path(a.out) / "report.html").string() << "\n";
  return unsafe ? Exit::Unsafe : failed ? Exit::CheckFailed : Exit::Ok;
}

Exit runUpdate(const GoldenArgs& a) {
  if (a.only != "missing" && a.only != "failed" && a.only != "all")
    throw UsageError("--only " + a.only + ": expected missing, failed or all");
  const GoldenManifest m = loadGoldenManifest(a.manifest);
  const std::vector<std::size_t> cases = selected(m, a.cases);
  const GoldenRun run = check(m, cases, true);
  int written = 0, unsafe = 0;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const CaseResult& r = run.results[k];
    bool missing = false, failed = false;
    for (const OutputResult& o : r.outputs)
      missing |= o.status == GoldenStatus::Missing, failed |= o.status == GoldenStatus::Failed;
    const bool take = a.only == "all" || missing || (a.only == "failed" && failed);
    if (!take) continue;
    if (!r.unsafe.empty()) {
      std::cerr << "kccd: golden update: " << r.id << ": the query's status is " << r.unsafe
                << " (unsafe): no golden written\n";
      ++unsafe;
      continue;
    }
    const std::string folder = goldenFolder(m, r.id);
    writeGoldens(run.renderings[k], folder);
    ++written;
    if (!a.quiet)
      std::cerr << "wrote " << folder << (missing ? " (was missing)" : failed ? " (was failing)" : "") << "\n";
  }
  std::cout << "golden update: " << written << " of " << cases.size() << " case(s) written (--only " << a.only << ")\n";
  return unsafe ? Exit::Unsafe : Exit::Ok;
}

Exit runApprove(const GoldenArgs& a) {
  const GoldenManifest m = loadGoldenManifest(a.manifest);
  const fs::path from(a.from);
  const std::string results_path = (from / "results.json").string();
  nlohmann::json results;
  try {
    results = nlohmann::json::parse(readRegularFile(results_path, 64u << 20, "golden results"));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(results_path + ": not the results of kccd golden run (" + std::string(e.what()) + ")");
  }
  if (!results.is_object() || results.value("kccd_golden_results", 0) != 1 || !results.contains("cases") ||
      !results["cases"].is_array())
    throw InputError(results_path + ": not the results of kccd golden run (no kccd_golden_results: 1 with cases)");
  std::set<std::string> ids;
  for (const GoldenCase& c : m.cases) ids.insert(c.id);
  // Everything checked before anything is written.
  struct Copy {
    fs::path from, to;
  };
  std::vector<Copy> copies;
  int approved = 0;
  for (const nlohmann::json& c : results["cases"]) {
    const std::string id = c.value("id", std::string());
    if (!ids.count(id)) throw InputError(results_path + ": case '" + printable(id, 60) + "' is not in " + m.path);
    bool any = false;
    for (const nlohmann::json& o : c.value("outputs", nlohmann::json::array())) {
      const nlohmann::json actual = o.value("actual", nlohmann::json::object());
      if (!actual.contains("file") || !actual["file"].is_string()) continue;
      const std::string file = actual["file"];
      const std::string output = o.value("output", std::string());
      if (file != id + "/" + output + ".actual.png")
        throw InputError(results_path + ": case '" + id + "': unexpected file '" + printable(file, 80) + "'");
      const std::string bytes = readRegularFile((from / file).string(), 1u << 30, "actual image");
      const std::string sha =
          sha256Hex(std::span<const unsigned char>(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()));
      if (sha != actual.value("sha256", std::string()))
        throw InputError((from / file).string() +
                         ": its SHA-256 is not the one the run recorded (changed since the run)");
      copies.push_back({from / file, fs::path(goldenFolder(m, id)) / (output + ".png")});
      any = true;
    }
    if (any) {
      copies.push_back({from / id / "golden.json", fs::path(goldenFolder(m, id)) / "golden.json"});
      ++approved;
    }
  }
  for (const Copy& c : copies) {
    const std::string bytes = readRegularFile(c.from.string(), 1u << 30, "approved file");
    fs::create_directories(c.to.parent_path());
    writeFileAtomically(c.to, bytes, "golden");
    if (!a.quiet) std::cerr << "approved " << c.to.string() << "\n";
  }
  std::cout << "golden approve: " << approved << " case(s) from " << a.from << "\n";
  return Exit::Ok;
}

Exit runList(const GoldenArgs& a) {
  const GoldenManifest m = loadGoldenManifest(a.manifest);
  std::set<std::string> ids;
  int missing = 0;
  for (const GoldenCase& c : m.cases) {
    ids.insert(c.id);
    std::string outs, absent;
    for (const GoldenOutput o : c.outputs) {
      outs += std::string(outs.empty() ? "" : ",") + goldenOutputName(o);
      if (!fs::exists(fs::path(goldenFolder(m, c.id)) / (std::string(goldenOutputName(o)) + ".png")))
        absent += std::string(absent.empty() ? "" : ",") + goldenOutputName(o);
    }
    missing += !absent.empty();
    std::cout << c.id << "\t"
              << (c.hasVideo()       ? "frame"
                  : !c.state.empty() ? "state"
                                     : "box")
              << "\t" << outs << "\t" << (absent.empty() ? "goldens present" : "missing: " + absent) << "\n";
  }
  int unused = 0;
  std::error_code ec;
  if (fs::is_directory(m.goldens, ec))
    for (const auto& e : fs::directory_iterator(m.goldens, ec))
      if (e.is_directory() && !ids.count(e.path().filename().string())) {
        std::cout << "unused golden: " << e.path().string() << "\n";
        ++unused;
      }
  std::cout << m.cases.size() << " case(s), " << missing << " with missing goldens, " << unused
            << " unused golden folder(s)\n";
  return Exit::Ok;
}

Exit guarded(Exit (*f)(const GoldenArgs&), const GoldenArgs& a) {
  try {
    return f(a);
  } catch (const render::GlContextError& e) {
    std::cerr << "kccd: golden: no usable GL context: " << oneLine(e.what()) << "\n";
    return Exit::Unsafe;
  }
}

}  // namespace

Runner addGolden(CLI::App& app) {
  CLI::App* g = app.add_subcommand(
      "golden",
      "Golden-image regression for your CI: render every case of a manifest (a model seen by a camera at a state,\n"
      "over a box, or on a recorded frame) and compare with the goldens kept in your repository. Exit 0 all passed,\n"
      "1 a case failed or its golden is missing, 2 bad manifest or input (nothing rendered), 3 no GL context or an\n"
      "unsafe query status.");
  g->require_subcommand(1);
  auto a = std::make_shared<GoldenArgs>();
  CLI::App* run = g->add_subcommand(
      "run", "Render, compare, report (results.json, junit.xml, summary.md, report.html); never writes goldens");
  CLI::App* update = g->add_subcommand(
      "update", "Render and write goldens with their golden.json (the inputs' hashes, renderer, version)");
  CLI::App* approve = g->add_subcommand(
      "approve", "Take the actual images of an earlier run (e.g. a CI artifact) as the goldens, hashes checked");
  CLI::App* list = g->add_subcommand("list", "The cases, their missing goldens, and golden folders no case uses");
  for (CLI::App* s : {run, update, approve, list})
    s->add_option("manifest", a->manifest, "The golden manifest (YAML)")->required();
  for (CLI::App* s : {run, update})
    s->add_option("--case", a->cases, "Only the cases whose id matches this glob (repeat for several)")
        ->allow_extra_args(false);
  run->add_option("--out", a->out, "Folder for the reports and the failing cases' images")->capture_default_str();
  run->add_flag("--keep-passing", a->keep_passing, "Write the images of passing cases too");
  update->add_option("--only", a->only, "Which cases: missing (no golden yet), failed (failing or missing), all")
      ->capture_default_str();
  approve->add_option("--from", a->from, "The --out folder of the run whose actual images become the goldens")
      ->required();
  for (CLI::App* s : {run, update, approve}) s->add_flag("-q,--quiet", a->quiet, "Print the summary and failures only");
  return [a, run, update, approve, list]() -> Exit {
    if (run->parsed()) return guarded(runRun, *a);
    if (update->parsed()) return guarded(runUpdate, *a);
    if (approve->parsed()) return guarded(runApprove, *a);
    (void)list;
    return guarded(runList, *a);
  };
}

}  // namespace kccd::cli
