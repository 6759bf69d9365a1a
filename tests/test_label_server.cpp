// `kccd calib label`'s server driven over HTTP on 127.0.0.1 (any free port): the session, a labels
// round trip that gives kccd calib's pose, a misclick rejected by name, a bad document refused with
// the labels reader's own message, the refusals of a local server (Host, Origin, content type,
// size), a save that writes exactly the files named and nothing else, the body under a point from
// the drawn volumes, and the autosave.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/labels.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"
#include "kccd/overlay/labelling/label_server.hpp"
#include "kccd/overlay/labelling/labels_document.hpp"
#include "kccd/render/model_view.hpp"
#include "support/cameras.hpp"
#include "support/files.hpp"

// Last: the OpenSSL headers it pulls in define names that clash with Eigen's when they come first.
#include <httplib.h>

namespace kccd::overlay {
namespace {

namespace fs = std::filesystem;
const std::string kData = KCCD_DATA_DIR;
const std::vector<double> kState = {0.3, 0.4, 0.6};  // the state of data/demo_labels.yaml's body labels

std::set<std::string> filesIn(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.insert(e.path().filename().string());
  return out;
}

std::string readText(const fs::path& p) { return kccd::testing::readText(p.string()); }

class LabelServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_label_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    model_ = std::make_unique<Model>(loadModel(kData + "/demo_arm.yaml"));
    labels_ = (dir_ / "labels.yaml").string();
    fs::copy_file(kData + "/demo_labels.yaml", labels_);
  }
  void TearDown() override {
    stopServer();
    session_.reset();
    fs::remove_all(dir_);
  }

  void start(const std::string& camera_output = "", const cv::Mat& mask = {}) {
    LabelSessionInputs in;
    if (!mask.empty()) {
      in.masks = {mask};
      in.mask_names = {"mask.png"};
    }
    in.intrinsics = intrinsicsOf(calib::loadCamera(kData + "/demo_camera.yaml"));
    in.intrinsics_name = "demo_camera.yaml";
    in.model = model_.get();
    in.camera_output = camera_output;
    LabelFrame f;
    f.name = "frame.png";
    f.bgr = cv::Mat(in.intrinsics.height, in.intrinsics.width, CV_8UC3, cv::Scalar(90, 100, 110));
    f.state = kState;
    f.labels_path = labels_;
    in.frames.push_back(f);
    session_ = std::make_unique<LabelSession>(std::move(in));
    server_ = std::make_unique<LabelServer>(*session_, LabelServerOptions{});
    thread_ = std::thread([this] { server_->run(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->port());
  }

  void stopServer() {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
    server_.reset();
  }

  nlohmann::json getJson(const std::string& path) {
    const auto res = client_->Get(path.c_str());
    EXPECT_TRUE(res);
    EXPECT_EQ(res->status, 200) << res->body;
    return nlohmann::json::parse(res->body);
  }

  httplib::Result putLabels(const nlohmann::json& doc, const httplib::Headers& headers = {}) {
    return client_->Put("/api/labels", headers, doc.dump(), "application/json");
  }

  fs::path dir_;
  std::string labels_;
  std::unique_ptr<Model> model_;
  std::unique_ptr<LabelSession> session_;
  std::unique_ptr<LabelServer> server_;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
};

// The page's first request: frames, the labels file's labels, the model's bodies, the solve.
TEST_F(LabelServerTest, TheSessionHasTheFramesLabelsBodiesAndTheSolve) {
  start();
  EXPECT_EQ(server_->url(), "http://127.0.0.1:" + std::to_string(server_->port()) + "/");
  const nlohmann::json s = getJson("/api/session");
  ASSERT_EQ(s["frames"].size(), 1u);
  EXPECT_EQ(s["frames"][0]["width"], 1280);
  EXPECT_EQ(s["frames"][0]["height"], 720);
  EXPECT_EQ(s["frames"][0]["image"], "/frame/0.png");
  EXPECT_EQ(s["frames"][0]["state"], nlohmann::json(kState));
  EXPECT_EQ(s["labels"], labelsJson(calib::loadLabels(kData + "/demo_labels.yaml")));
  EXPECT_EQ(s["bodies"].size(), model_->bodies.size());
  EXPECT_EQ(s["solve"]["status"], "solved") << s["solve"].dump();
  EXPECT_EQ(s["dirty"], false);
  // Projected model points at the estimate are candidates to label.
  EXPECT_FALSE(s["candidates"]["model_points"].empty());

  // The frame as PNG, the volumes at the estimate as an RGBA layer of the frame's size.
  const auto frame = client_->Get("/frame/0.png");
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->get_header_value("Content-Type"), "image/png");
  const cv::Mat decoded =
      cv::imdecode(std::vector<unsigned char>(frame->body.begin(), frame->body.end()), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(decoded.size(), cv::Size(1280, 720));
  const auto layer = client_->Get("/overlay/0.png?rev=0");
  ASSERT_TRUE(layer);
  const cv::Mat rgba =
      cv::imdecode(std::vector<unsigned char>(layer->body.begin(), layer->body.end()), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(rgba.type(), CV_8UC4);
  std::vector<cv::Mat> channels;
  cv::split(rgba, channels);
  EXPECT_GT(cv::countNonZero(channels[3]), 5000) << "the arm's volumes cover part of the frame";
  EXPECT_EQ(client_->Get("/frame/1.png")->status, 404);
  EXPECT_EQ(client_->Get("/api/nothing")->status, 404);
}

// The labels back as the page sends them: the same solve as kccd calib's library calls on the
// saved file, bit for bit; the save writes the labels file (the old one kept) and the camera.
TEST_F(LabelServerTest, ALabelsRoundTripGivesKccdCalibsPose) {
  const std::string camera = (dir_ / "camera.yaml").string();
  start(camera);
  const std::set<std::string> before = filesIn(dir_);
  const nlohmann::json s = getJson("/api/session");
  const auto put = putLabels(s["labels"]);
  ASSERT_TRUE(put);
  ASSERT_EQ(put->status, 200) << put->body;
  const nlohmann::json solve = nlohmann::json::parse(put->body);
  EXPECT_EQ(solve["status"], "solved");
  EXPECT_EQ(solve["revision"], 1);
  EXPECT_EQ(getJson("/api/session")["dirty"], true);

  const auto saved = client_->Post("/api/save", "{}", "application/json");
  ASSERT_TRUE(saved);
  ASSERT_EQ(saved->status, 200) << saved->body;
  const nlohmann::json paths = nlohmann::json::parse(saved->body);
  EXPECT_EQ(paths["labels"], nlohmann::json({labels_}));
  EXPECT_EQ(paths["backups"], nlohmann::json({labels_ + ".bak"}));
  EXPECT_EQ(paths["camera"], camera);
  std::set<std::string> expected = before;
  expected.insert({"labels.yaml.bak", "camera.yaml"});
  EXPECT_EQ(filesIn(dir_), expected) << "only the labels file, its backup and the camera file";
  EXPECT_EQ(readText(labels_ + ".bak"), readText(kData + "/demo_labels.yaml"));

  // kccd calib's library calls on the saved labels: the same pose, bit for bit.
  GatherInputs g;
  g.camera = intrinsicsOf(calib::loadCamera(kData + "/demo_camera.yaml"));
  g.camera_name = "cam";
  g.model = model_.get();
  CalibFrame f;
  f.image = "frame.png";
  f.bgr = cv::Mat(720, 1280, CV_8UC3, cv::Scalar(90, 100, 110));
  f.labels = calib::loadLabels(labels_);
  f.state = kState;
  g.frames.push_back(f);
  const CalibSolution ref = solveCalibration(g.camera, gatherCorrespondences(g), calib::PoseOptions{}, model_.get());
  ASSERT_TRUE(ref.solved());
  const calib::Camera written = calib::loadCamera(camera);
  EXPECT_EQ(written.rvec, ref.pose.camera.rvec);
  EXPECT_EQ(written.tvec, ref.pose.camera.tvec);
  EXPECT_EQ(solve["reprojection_rms_px"].get<double>(), *ref.pose.camera.reprojection_rms_px);
  EXPECT_EQ(getJson("/api/session")["dirty"], false);
}

// A misclick: one label 60 px off is rejected by name; its residual is large.
TEST_F(LabelServerTest, AMisclickIsRejectedByName) {
  start();
  const nlohmann::json s = getJson("/api/session");
  // The demo's labels hold one misclick already (post_top_misclick): rejected before and after.
  std::set<std::string> rejected = s["solve"]["rejected"].get<std::set<std::string>>();
  ASSERT_EQ(rejected, std::set<std::string>{"post_top_misclick"});
  nlohmann::json doc = s["labels"];
  nlohmann::json& moved = doc["labels"][3];
  const std::string name = moved["name"];
  moved["pixel"][0] = moved["pixel"][0].get<double>() + 60.0;
  const auto put = putLabels(doc);
  ASSERT_EQ(put->status, 200) << put->body;
  const nlohmann::json solve = nlohmann::json::parse(put->body);
  EXPECT_EQ(solve["status"], "solved");
  rejected.insert(name);
  EXPECT_EQ(solve["rejected"].get<std::set<std::string>>(), rejected);
  for (const nlohmann::json& r : solve["residuals"]) {
    if (r["name"] == name) {
      EXPECT_GT(r["px"].get<double>(), 40.0);
    }
  }
}

// A document that cannot be used: 400 with the message the labels reader gives the same labels
// saved (file:line:col: field: problem), and nothing changes.
TEST_F(LabelServerTest, ABadDocumentIsRefusedWithTheReadersMessage) {
  start();
  const nlohmann::json before = getJson("/api/session");
  const nlohmann::json bad = {{"labels", {{{"name", "a"}, {"pixel", {1.0}}, {"world", {0, 0, 0}}}}}};
  const auto put = putLabels(bad);
  ASSERT_EQ(put->status, 400);
  std::string expected;
  try {
    (void)calib::parseLabels(labelsYaml(bad, labels_), labels_);
  } catch (const calib::LabelsError& e) {
    expected = e.what();
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(nlohmann::json::parse(put->body)["error"], expected);
  EXPECT_EQ(expected.rfind(labels_ + ":2:", 0), 0u) << expected;  // the line the saved file would have it on
  // A body label without a model's body, and a body that does not exist: refused as kccd calib would.
  const nlohmann::json unknown = {
      {"labels", {{{"name", "b"}, {"pixel", {1, 2}}, {"body", "nope"}, {"point", {0, 0, 0}}}}}};
  const auto put2 = putLabels(unknown);
  EXPECT_EQ(put2->status, 400);
  EXPECT_NE(put2->body.find("nope"), std::string::npos) << put2->body;
  EXPECT_EQ(putLabels(nlohmann::json::array())->status, 400);
  EXPECT_EQ(client_->Put("/api/labels", "{not json", "application/json")->status, 400);
  EXPECT_EQ(client_->Put("/api/labels?frame=7", "{\"labels\": []}", "application/json")->status, 404);
  const nlohmann::json after = getJson("/api/session");
  EXPECT_EQ(after["labels"], before["labels"]);
  EXPECT_EQ(after["solve"], before["solve"]);
  EXPECT_EQ(after["dirty"], false);
}

// What a local server refuses: another Host (DNS rebinding), a write from another origin or not
// sent as JSON, a body over the limit. Nothing changes.
TEST_F(LabelServerTest, ForeignHostsOriginsFormsAndHugeBodiesAreRefused) {
  start();
  const std::string port = std::to_string(server_->port());
  const nlohmann::json doc = getJson("/api/session")["labels"];
  EXPECT_EQ(client_->Get("/api/session", {{"Host", "attacker.example:" + port}})->status, 421);
  EXPECT_EQ(client_->Get("/", {{"Host", "localhost:" + port}})->status, 200);
  EXPECT_EQ(putLabels(doc, {{"Origin", "http://attacker.example"}})->status, 403);
  EXPECT_EQ(client_->Put("/api/labels", doc.dump(), "text/plain")->status, 415);
  EXPECT_EQ(client_->Post("/api/save", "labels=x", "application/x-www-form-urlencoded")->status, 415);
  EXPECT_EQ(client_->Put("/api/labels", std::string(2 << 20, ' '), "application/json")->status, 413);
  EXPECT_EQ(client_->Get("/../../etc/passwd")->status, 404);
  EXPECT_FALSE(fs::exists(labels_ + ".bak")) << "nothing refused was autosaved";
  EXPECT_EQ(getJson("/api/session")["revision"], 0);
  EXPECT_EQ(putLabels(doc, {{"Origin", "http://127.0.0.1:" + port}})->status, 200);
}

// A point placed on the drawn volumes: the body there, and its points nearest in the image first.
// Each model point's own pixel either shows its body (then it is listed first, 0 px away) or a
// body nearer the camera hiding it; most are not hidden.
TEST_F(LabelServerTest, TheVolumesPickTheBodyUnderAPoint) {
  start();
  const nlohmann::json s = getJson("/api/session");
  ASSERT_EQ(s["solve"]["status"], "solved");
  std::set<std::string> bodies;
  for (const nlohmann::json& b : s["bodies"]) bodies.insert(b["name"].get<std::string>());
  int own = 0, total = 0;
  for (const nlohmann::json& m : s["candidates"]["model_points"]) {
    const double u = m["pixel"][0], v = m["pixel"][1];
    if (!(u >= 0 && v >= 0 && u <= 1279 && v <= 719)) continue;
    ++total;
    const nlohmann::json r = getJson("/api/pick?frame=0&x=" + std::to_string(u) + "&y=" + std::to_string(v));
    ASSERT_TRUE(r["body"].is_string()) << m.dump() << " lies inside its own volume, so some volume is drawn there";
    EXPECT_TRUE(bodies.count(r["body"].get<std::string>()));
    ASSERT_FALSE(r["points"].empty());
    double last = 0;
    for (const nlohmann::json& p : r["points"]) {
      EXPECT_EQ(p["body"], r["body"]);
      EXPECT_GE(p["distance_px"].get<double>(), last);
      last = p["distance_px"];
    }
    if (r["body"] == m["body"]) {
      ++own;
      EXPECT_LT(r["points"][0]["distance_px"].get<double>(), 1e-3);
    }
  }
  ASSERT_GE(total, 4);
  EXPECT_GE(own * 2, total) << own << " of " << total << " model points show their own body";

  // Where the overlay layer is transparent no volume is drawn: no body.
  const auto layer = client_->Get("/overlay/0.png");
  const cv::Mat rgba =
      cv::imdecode(std::vector<unsigned char>(layer->body.begin(), layer->body.end()), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(rgba.at<cv::Vec4b>(0, 0)[3], 0);
  EXPECT_TRUE(getJson("/api/pick?frame=0&x=0&y=0")["body"].is_null());
  EXPECT_TRUE(getJson("/api/pick?frame=0&x=-5&y=3e8")["body"].is_null());
  for (const char* bad : {"/api/pick?frame=0&x=abc&y=1", "/api/pick?frame=0&x=nan&y=1", "/api/pick?frame=0&x=1",
                          "/api/pick?frame=0&x=1e999&y=1"})
    EXPECT_EQ(client_->Get(bad)->status, 400) << bad;
  EXPECT_EQ(client_->Get("/api/pick?frame=3&x=1&y=1")->status, 404);
}

// Every accepted edit is autosaved to LABELS.yaml.bak; a session started later offers it back while
// it is newer than the labels file; a save makes the .bak the version before again.
TEST_F(LabelServerTest, EditsAreAutosavedAndOfferedAgain) {
  const std::string original = readText(labels_);
  start();
  nlohmann::json doc = getJson("/api/session")["labels"];
  doc["labels"][0]["pixel"][0] = doc["labels"][0]["pixel"][0].get<double>() + 1.25;
  ASSERT_EQ(putLabels(doc)->status, 200);
  EXPECT_EQ(readText(labels_), original) << "the labels file is written by save only";
  EXPECT_EQ(readText(labels_ + ".bak"), labelsYaml(doc, labels_));
  stopServer();
  session_.reset();

  start();  // the page was closed without saving
  nlohmann::json s = getJson("/api/session");
  ASSERT_TRUE(s["frames"][0]["recovered"].is_object());
  EXPECT_EQ(s["frames"][0]["recovered"]["file"], labels_ + ".bak");
  EXPECT_EQ(s["frames"][0]["recovered"]["labels"], doc);
  EXPECT_EQ(s["labels"], labelsJson(calib::parseLabels(original, labels_))) << "the labels file is what loads";
  ASSERT_EQ(putLabels(doc)->status, 200);  // restored
  EXPECT_TRUE(getJson("/api/session")["frames"][0]["recovered"].is_null());
  ASSERT_EQ(client_->Post("/api/save", "{}", "application/json")->status, 200);
  EXPECT_EQ(readText(labels_), labelsYaml(doc, labels_));
  EXPECT_EQ(readText(labels_ + ".bak"), original);
  stopServer();
  session_.reset();

  start();  // saved: nothing to offer, and the saved file loads back exactly as it was sent
  const nlohmann::json again = getJson("/api/session");
  EXPECT_TRUE(again["frames"][0]["recovered"].is_null());
  EXPECT_EQ(again["labels"], doc);
}

// The page itself: built in, with a content security policy that allows nothing from elsewhere.
TEST_F(LabelServerTest, ThePageIsServedFromTheProgram) {
  start();
  const auto page = client_->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<script type=\"module\" src=\"/app.js\">"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'self'"), std::string::npos);
  for (const char* file : {"/app.js", "/view.js", "/undo.js", "/labels.js", "/app.css"}) {
    const auto res = client_->Get(file);
    ASSERT_TRUE(res) << file;
    EXPECT_EQ(res->status, 200) << file;
    EXPECT_GT(res->body.size(), 500u) << file;
  }
  EXPECT_EQ(client_->Get("/missing.js")->status, 404);
}

// POST /api/quit ends run().
TEST_F(LabelServerTest, QuitEndsTheServer) {
  start();
  const auto res = client_->Post("/api/quit", "{}", "application/json");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  thread_.join();  // returns: the server has stopped
  EXPECT_FALSE(client_->Get("/api/session"));
}

// A labels file that does not exist yet is an empty session; one that cannot be read is an error.
TEST_F(LabelServerTest, NewAndBadLabelsFiles) {
  fs::remove(labels_);
  start();
  const nlohmann::json s = getJson("/api/session");
  EXPECT_EQ(s["labels"], nlohmann::json({{"labels", nlohmann::json::array()}}));
  EXPECT_NE(s["solve"]["status"], "solved");
  const auto saved = client_->Post("/api/save", "{}", "application/json");
  EXPECT_EQ(nlohmann::json::parse(saved->body)["labels"], nlohmann::json::array());
  EXPECT_FALSE(fs::exists(labels_)) << "nothing labelled: no file written";
  EXPECT_TRUE(getJson("/api/pick?frame=0&x=640&y=360")["body"].is_null()) << "not solved: no volumes drawn";
  stopServer();
  session_.reset();
  std::ofstream(labels_) << "labels: [{name: a, pixel: [1, 2]}]\n";
  EXPECT_THROW(start(), calib::LabelsError);
}

// Snap to the robot: four clicks 6 px off and a misclick do not solve (at least 6 are needed); with a robot mask
// (drawn by the GL renderer at the sample camera, not by calib's silhouette) the snap refines the rough
// pose from the four to the camera, the overlay draws both outlines, unchecking goes back, and a
// save writes the snapped camera with its refinement figures.
TEST_F(LabelServerTest, SnapToTheRobotFromFourRoughClicksAndAMisclick) {
  const calib::Camera truth = calib::loadCamera(kData + "/demo_camera.yaml");
  render::ModelView view(*model_, truth);
  render::ModelViewRequest request;
  request.state = kState;
  request.mask = true;
  const cv::Mat mask = view.draw(request).images.mask != 0;
  std::ofstream(labels_) << "labels:\n"
                            "  - {name: pedestal_0, pixel: [554.6, 444.3], world: [0, 0, 0]}\n"
                            "  - {name: table_1, pixel: [704.6, 650.5], world: [0.95, -0.4, 0.1]}\n"
                            "  - {name: upper_arm_1, pixel: [671.0, 368.5], body: upper_arm, point: [0.4, 0, 0]}\n"
                            "  - {name: gripper_3, pixel: [767.9, 525.5], body: gripper, point: [0.42, 0.04, 0]}\n"
                            "  - {name: post_misclick, pixel: [758.1, 538.7], world: [0.6, 0, 0]}\n";  // 40 px off
  const std::string camera = (dir_ / "camera.yaml").string();
  start(camera, mask);
  nlohmann::json s = getJson("/api/session");
  EXPECT_EQ(s["solve"]["snap"]["available"], true);
  EXPECT_EQ(s["solve"]["snap"]["on"], false);
  EXPECT_NE(s["solve"]["status"], "solved");

  auto on = client_->Post("/api/snap", R"({"on": true})", "application/json");
  ASSERT_TRUE(on);
  ASSERT_EQ(on->status, 200) << on->body;
  const nlohmann::json snapped = nlohmann::json::parse(on->body);
  ASSERT_EQ(snapped["status"], "solved") << snapped.dump(1);
  EXPECT_EQ(snapped["snap"]["on"], true);
  EXPECT_EQ(snapped["refinement"]["start"], "points");
  EXPECT_GT(snapped["refinement"]["frames"][0]["iou_after"].get<double>(), 0.95);
  EXPECT_EQ(snapped["revision"], 1);
  // The rough clicks agree with the snapped pose; the misclick is named.
  EXPECT_EQ(snapped["rejected"], nlohmann::json({"post_misclick"})) << snapped.dump(1);
  // The overlay carries the mask's outline (yellow) and the drawn robot's (magenta), opaque.
  const auto png = client_->Get("/overlay/0.png");
  ASSERT_TRUE(png);
  const cv::Mat layer =
      cv::imdecode(std::vector<unsigned char>(png->body.begin(), png->body.end()), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(layer.type(), CV_8UC4);
  cv::Mat magenta, yellow;
  cv::inRange(layer, cv::Scalar(200, 0, 200, 255), cv::Scalar(255, 60, 255, 255), magenta);
  cv::inRange(layer, cv::Scalar(0, 170, 200, 255), cv::Scalar(60, 255, 255, 255), yellow);
  EXPECT_GT(cv::countNonZero(magenta), 200);
  EXPECT_GT(cv::countNonZero(yellow), 10);  // where the outlines agree, the drawn one covers the mask's

  // Saved: the snapped camera, near the true one, with the refinement's figures.
  const auto saved = client_->Post("/api/save", "{}", "application/json");
  ASSERT_TRUE(saved);
  ASSERT_EQ(saved->status, 200) << saved->body;
  const calib::Camera written = calib::loadCamera(camera);
  const double rot = kccd::testing::rotationErrorDeg(written.rvec, truth.rvec);
  const double pos = cv::norm(kccd::testing::cameraCentre(written) - kccd::testing::cameraCentre(truth));
  std::printf("4 clicks 6 px off, snapped: %.3f deg, %.2f mm from the sample camera\n", rot, pos * 1e3);
  EXPECT_LT(rot, 0.2);
  EXPECT_LT(pos, 0.01);
  EXPECT_NE(readText(camera).find("refinement: masks"), std::string::npos);

  // An edit while snapping is snapped again; with fewer than 4 points there is no start, said.
  nlohmann::json two = getJson("/api/session")["labels"];
  two["labels"] = nlohmann::json::array({two["labels"][0], two["labels"][1]});
  const auto few = putLabels(two);
  ASSERT_TRUE(few);
  ASSERT_EQ(few->status, 200) << few->body;
  const nlohmann::json unsnapped = nlohmann::json::parse(few->body);
  EXPECT_NE(unsnapped["status"], "solved");
  EXPECT_EQ(unsnapped["snap"]["on"], true);
  EXPECT_FALSE(unsnapped["snap"]["message"].get<std::string>().empty()) << unsnapped.dump(1);
  EXPECT_FALSE(unsnapped.contains("refinement"));
  const auto back = putLabels(s["labels"]);
  ASSERT_TRUE(back);
  EXPECT_EQ(nlohmann::json::parse(back->body)["status"], "solved") << back->body;

  // Unchecked: back to the points' solve (not solved).
  auto off = client_->Post("/api/snap", R"({"on": false})", "application/json");
  ASSERT_TRUE(off);
  ASSERT_EQ(off->status, 200) << off->body;
  EXPECT_NE(nlohmann::json::parse(off->body)["status"], "solved");
  EXPECT_FALSE(nlohmann::json::parse(off->body).contains("refinement"));
  const auto bad = client_->Post("/api/snap", R"({"on": "yes"})", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
}

TEST_F(LabelServerTest, SnapWithoutMasksIsRefused) {
  start();
  EXPECT_EQ(getJson("/api/session")["solve"]["snap"]["available"], false);
  const auto r = client_->Post("/api/snap", R"({"on": true})", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409);
  EXPECT_NE(r->body.find("--masks"), std::string::npos) << r->body;
}

}  // namespace
}  // namespace kccd::overlay
