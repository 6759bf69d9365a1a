#include "kccd/overlay/golden/golden_report.hpp"

#include <filesystem>
#include <sstream>

#include <openssl/evp.h>

#include "kccd/format_number.hpp"
#include "kccd/overlay/common/staged_output.hpp"

namespace kccd::overlay {
namespace {

namespace fs = std::filesystem;

std::string bytesOf(const std::vector<unsigned char>& v) { return std::string(v.begin(), v.end()); }

std::string base64(const std::vector<unsigned char>& bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int n =
      EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), bytes.data(), static_cast<int>(bytes.size()));
  out.resize(static_cast<std::size_t>(n));
  return out;
}

std::string xmlEscape(const std::string& s) {
  std::string o;
  for (const char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      case '\'':
        o += "&apos;";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t')
          o += ' ';
        else
          o += c;
    }
  }
  return o;
}

bool keep(const CaseResult& r, bool keep_passing) { return keep_passing || !r.passed(); }

std::string caseStatus(const CaseResult& r) {
  if (r.passed()) return "passed";
  for (const OutputResult& o : r.outputs)
    if (o.status == GoldenStatus::Failed) return "failed";
  return r.unsafe.empty() ? "missing" : "failed";
}

// The evidence pictures of one output: expected, actual, diff, crop (PNG bytes; empty: none).
struct Evidence {
  std::vector<unsigned char> expected, actual, diff, crop;
};

Evidence evidenceOf(const OutputResult& o, const GoldenImage& img) {
  Evidence e;
  const bool mask = o.output == GoldenOutput::Mask;
  e.actual = img.png;
  if (o.expected.empty()) return e;
  e.expected = deterministicPng(o.expected);
  const cv::Mat diff = diffPicture(o.expected, img.image, o.comparison, mask);
  e.diff = deterministicPng(diff);
  if (!o.comparison.largest_cluster.empty()) {
    // Expected | actual | diff around the largest cluster, 8x, side by side.
    std::vector<cv::Mat> parts;
    for (const cv::Mat& shown : {picture(o.expected, mask), picture(img.image, mask), diff})
      parts.push_back(magnifiedCrop(shown, o.comparison.largest_cluster));
    if (parts[0].size() == parts[1].size() && parts[1].size() == parts[2].size()) {
      const cv::Mat gap(parts[0].rows, 6, CV_8UC3, cv::Scalar(255, 255, 255));
      cv::Mat row;
      cv::hconcat(std::vector<cv::Mat>{parts[0], gap, parts[1], gap, parts[2]}, row);
      e.crop = deterministicPng(row);
    }
  }
  return e;
}

nlohmann::json metrics(const Comparison& c) {
  return {{"identical", c.identical},
          {"changed_px", c.changed_px},
          {"largest_cluster_px", c.largest_cluster_px},
          {"worst_centroid_shift_px", c.worst_centroid_shift_px},
          {"worst_area_change_ratio", c.worst_area_change_ratio}};
}

}  // namespace

std::string goldenSummaryLine(const GoldenRun& run) {
  int passed = 0, failed = 0, missing = 0;
  for (const CaseResult& r : run.results) {
    const std::string s = caseStatus(r);
    (s == "passed" ? passed : s == "failed" ? failed : missing) += 1;
  }
  return std::to_string(run.results.size()) + " case(s): " + std::to_string(passed) + " passed, " +
         std::to_string(failed) + " failed, " + std::to_string(missing) + " missing";
}

void writeGoldenReports(const GoldenRun& run, const std::string& folder, bool keep_passing) {
  fs::create_directories(folder);
  const GoldenManifest& m = *run.manifest;
  nlohmann::json cases = nlohmann::json::array();
  std::ostringstream junit, md, html;
  int failures = 0, tests = 0;
  std::ostringstream junit_cases;
  md << "# Golden images: " << goldenSummaryLine(run) << "\n\nManifest `" << m.path << "`, kccd " << kccdVersion()
     << ", renderer `" << run.renderer << "`, " << formatNumber(run.seconds, 3)
     << " s.\n\n| case | output | status | reason |\n|---|---|---|---|\n";
  html << "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>kccd golden: "
       << xmlEscape(goldenSummaryLine(run))
       << "</title><style>body{font:14px system-ui,sans-serif;margin:16px;background:#fafafa;color:#222}"
          "table{border-collapse:collapse}td,th{padding:3px 8px;border-bottom:1px solid "
          "#ddd;text-align:left;vertical-align:top}"
          ".passed{color:#197a19}.failed,.missing{color:#b3261e;font-weight:600}img{image-rendering:pixelated;max-"
          "width:100%;"
          "border:1px solid #ccc}.row{display:flex;gap:8px}.row figure{margin:0;flex:1}figcaption{color:#666}"
          "section{background:#fff;border:1px solid #ddd;padding:8px 12px;margin:12px 0}</style></head><body>\n"
       << "<h1>kccd golden: " << xmlEscape(goldenSummaryLine(run)) << "</h1><p>Manifest <code>" << xmlEscape(m.path)
       << "</code>, kccd " << kccdVersion() << ", renderer <code>" << xmlEscape(run.renderer)
       << "</code>.</p>\n<table><tr><th>case</th><th>output</th>"
       << "<th>status</th><th>reason</th></tr>\n";
  std::ostringstream sections, causes;
  for (std::size_t k = 0; k < run.results.size(); ++k) {
    const CaseResult& r = run.results[k];
    const GoldenRendering& rendering = run.renderings[k];
    const bool kept = keep(r, keep_passing);
    const fs::path case_dir = fs::path(folder) / r.id;
    if (kept) {
      fs::create_directories(case_dir);
      writeFileAtomically(case_dir / "golden.json", rendering.sidecar.dump(2) + "\n", "golden sidecar");
    }
    nlohmann::json outs = nlohmann::json::array();
    if (!r.unsafe.empty()) {
      ++tests, ++failures;
      junit_cases << "  <testcase classname=\"kccd.golden." << xmlEscape(r.id)
                  << "\" name=\"query\"><failure message=\"the query's status is " << xmlEscape(r.unsafe)
                  << ": unsafe, the images cannot be trusted\"/></testcase>\n";
    }
    for (std::size_t i = 0; i < r.outputs.size(); ++i) {
      const OutputResult& o = r.outputs[i];
      const GoldenImage& img = rendering.images[i];
      const std::string name = goldenOutputName(o.output);
      nlohmann::json entry = {{"output", name},
                              {"status", goldenStatusName(o.status)},
                              {"reason", o.reason},
                              {"tolerance", o.tolerance},
                              {"actual", {{"sha256", img.sha256}, {"file", nullptr}}}};
      if (o.status != GoldenStatus::Missing) entry["metrics"] = metrics(o.comparison);
      std::string figures;
      if (kept) {
        const Evidence e = evidenceOf(o, img);
        const std::string base = r.id + "/" + name;
        writeFileAtomically(fs::path(folder) / (base + ".actual.png"), bytesOf(e.actual), "golden evidence");
        entry["actual"]["file"] = base + ".actual.png";
        if (!e.expected.empty())
          writeFileAtomically(fs::path(folder) / (base + ".expected.png"), bytesOf(e.expected), "golden evidence");
        if (!e.diff.empty())
          writeFileAtomically(fs::path(folder) / (base + ".diff.png"), bytesOf(e.diff), "golden evidence");
        if (!e.crop.empty())
          writeFileAtomically(fs::path(folder) / (base + ".crop.png"), bytesOf(e.crop), "golden evidence");
        const bool mask = o.output == GoldenOutput::Mask;
        const auto fig = [&](const std::vector<unsigned char>& png, const std::string& caption) {
          if (png.empty()) return std::string();
          return "<figure><img alt=\"" + caption + "\" src=\"data:image/png;base64," + base64(png) + "\"><figcaption>" +
                 caption + "</figcaption></figure>";
        };
        std::vector<unsigned char> shown_e = e.expected, shown_a = e.actual;
        if (mask) {  // label values are invisible as grey: false colour for people
          shown_a = deterministicPng(falseColour(img.image));
          if (!o.expected.empty()) shown_e = deterministicPng(falseColour(o.expected));
        }
        figures = "<div class=\"row\">" + fig(shown_e, "expected") + fig(shown_a, "actual") +
                  fig(e.diff, "diff (changed pixels red)") + "</div>" +
                  (e.crop.empty()
                       ? ""
                       : "<div class=\"row\">" +
                             fig(e.crop, "8&times; around the largest cluster: expected | actual | diff") + "</div>");
      }
      outs.push_back(entry);
      ++tests;
      const bool bad = o.status != GoldenStatus::Passed;
      failures += bad;
      const std::string line = o.reason.empty() ? "identical" : o.reason;
      junit_cases << "  <testcase classname=\"kccd.golden." << xmlEscape(r.id) << "\" name=\"" << name << "\">";
      if (bad)
        junit_cases << "<failure message=\"" << xmlEscape(line + (r.cause.empty() ? "" : "; likely cause: " + r.cause))
                    << "\"/>";
      junit_cases << "</testcase>\n";
      md << "| " << r.id << " | " << name << " | " << goldenStatusName(o.status) << " | " << line << " |\n";
      html << "<tr><td><a href=\"#" << xmlEscape(r.id) << "-" << name << "\">" << xmlEscape(r.id) << "</a></td><td>"
           << name << "</td><td class=\"" << goldenStatusName(o.status) << "\">" << goldenStatusName(o.status)
           << "</td><td>" << xmlEscape(line) << "</td></tr>\n";
      if (kept) {
        std::string tol;
        for (const auto& [k2, v] : o.tolerance.items())
          if (k2 != "from") tol += (tol.empty() ? "" : ", ") + k2 + " " + v.dump();
        sections << "<section id=\"" << xmlEscape(r.id) << "-" << name << "\"><h2>" << xmlEscape(r.id) << " &middot; "
                 << name << " &middot; <span class=\"" << goldenStatusName(o.status) << "\">"
                 << goldenStatusName(o.status) << "</span></h2><p>" << xmlEscape(line) << "</p>"
                 << (r.cause.empty() ? "" : "<p><b>Likely cause:</b> " + xmlEscape(r.cause) + "</p>")
                 << "<p>Tolerances: " << xmlEscape(tol) << " (from "
                 << xmlEscape(o.tolerance.value("from", std::string("built-in"))) << ")</p>" << figures
                 << "</section>\n";
      }
    }
    cases.push_back({{"id", r.id},
                     {"status", caseStatus(r)},
                     {"cause", r.cause.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.cause)},
                     {"unsafe", r.unsafe.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.unsafe)},
                     {"outputs", outs}});
    if (!r.cause.empty()) causes << "- " << r.id << ": " << r.cause << "\n";
    if (!r.unsafe.empty())
      causes << "- " << r.id << ": the query's status is " << r.unsafe << " (unsafe: its images cannot be trusted)\n";
  }
  if (!causes.str().empty()) md << "\n## Likely causes\n\n" << causes.str();
  html << "</table>\n" << sections.str() << "</body></html>\n";
  const nlohmann::json results = {{"kccd_golden_results", 1},
                                  {"manifest", m.path},
                                  {"kccd_version", kccdVersion()},
                                  {"renderer", run.renderer},
                                  {"seconds", run.seconds},
                                  {"summary", goldenSummaryLine(run)},
                                  {"cases", cases}};
  junit << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"kccd golden\" tests=\"" << tests
        << "\" failures=\"" << failures << "\" time=\"" << formatNumber(run.seconds, 4) << "\">\n"
        << junit_cases.str() << "</testsuite>\n";
  writeFileAtomically(fs::path(folder) / "results.json", results.dump(2) + "\n", "golden results");
  writeFileAtomically(fs::path(folder) / "junit.xml", junit.str(), "golden JUnit");
  writeFileAtomically(fs::path(folder) / "summary.md", md.str(), "golden summary");
  writeFileAtomically(fs::path(folder) / "report.html", html.str(), "golden report");
}

}  // namespace kccd::overlay
