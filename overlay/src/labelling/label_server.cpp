#include "kccd/overlay/labelling/label_server.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>
#include <utility>

#include <httplib.h>

#include "kccd/file_reader.hpp"

namespace kccd::overlay {
namespace {

// The deepest nesting of arrays and objects in a JSON text (strings skipped): the parsed
// document's copies and destruction recurse once per level.
int jsonDepth(const std::string& text) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

constexpr const char* kJson = "application/json";

void sendJson(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), kJson);
}

void sendError(httplib::Response& res, int status, const std::string& message) {
  sendJson(res, status, nlohmann::json{{"error", message}});
}

void sendPng(httplib::Response& res, const std::vector<unsigned char>& png, bool cacheable) {
  res.status = 200;
  res.set_header("Cache-Control", cacheable ? "max-age=3600" : "no-store");
  res.set_content(reinterpret_cast<const char*>(png.data()), png.size(), "image/png");
}

// A small whole number, or -1 when `s` is not one.
long parseIndex(const std::string& s) {
  if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stol(s);
}

// The index in a path's first match, or -1 when it is not a small whole number.
long frameIndex(const httplib::Request& req) { return req.matches.size() < 2 ? -1 : parseIndex(req.matches[1]); }

}  // namespace

struct LabelServer::Impl {
  LabelSession& session;
  LabelServerOptions options;
  httplib::Server server;
  // stop() may come before run() listens (a signal right after the address is printed): it is
  // remembered, and repeated until run() has returned.
  std::atomic<bool> stop_requested{false}, started{false}, finished{false};
  std::mutex mutex;  // one request at a time touches the session
  int port = 0;
  std::set<std::string> hosts;  // the Host values this server answers
  std::thread stopper;
  std::function<void(const std::string&, const std::string&, int)> log;

  Impl(LabelSession& s, LabelServerOptions o) : session(s), options(std::move(o)) {}

  // The page's file named `name` (built in, or from --web-root: the same names only).
  bool webFile(const std::string& name, std::string& body, std::string& type) const {
    const std::string* builtin = builtinWebFile(name, type);
    if (!builtin) return false;
    if (options.web_root.empty()) {
      body = *builtin;
      return true;
    }
    const std::string file = name == "/" ? "index.html" : name.substr(1);
    body = readRegularFile((std::filesystem::path(options.web_root) / file).string(), 16u << 20, "web file");
    return true;
  }

  // Refuses what a local server must not answer: another Host (DNS rebinding), a write from
  // another origin or not sent as JSON (a cross-site form can send neither).
  httplib::Server::HandlerResponse screen(const httplib::Request& req, httplib::Response& res) const {
    const std::string host = req.get_header_value("Host");
    if (hosts.count(host) == 0) {
      sendError(res, 421, "this server answers requests for " + *hosts.begin() + " only, not '" + host + "'");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (req.method == "GET" || req.method == "HEAD") return httplib::Server::HandlerResponse::Unhandled;
    if (req.has_header("Origin")) {
      const std::string origin = req.get_header_value("Origin");
      if (origin.rfind("http://", 0) != 0 || hosts.count(origin.substr(7)) == 0) {
        sendError(res, 403, "a write from another origin ('" + origin + "') is refused");
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    if (req.get_header_value("Content-Type").rfind(kJson, 0) != 0) {
      sendError(res, 415, "writes are JSON: send Content-Type: application/json");
      return httplib::Server::HandlerResponse::Handled;
    }
    // The body's size is bounded by its Content-Length only: a chunked or compressed body (which
    // the library would read or inflate without that bound) is refused before it is read.
    if (req.has_header("Transfer-Encoding") || !req.has_header("Content-Length")) {
      sendError(res, 411, "writes give their Content-Length (no chunked transfer)");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (req.has_header("Content-Encoding")) {
      sendError(res, 415, "writes are plain JSON (no Content-Encoding)");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  }

  void routes() {
    server.set_payload_max_length(options.max_request_bytes);
    server.set_pre_routing_handler(
        [this](const httplib::Request& req, httplib::Response& res) { return screen(req, res); });
    server.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
      if (log) log(req.method, req.path, res.status);
    });
    server.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
      try {
        std::rethrow_exception(ep);
      } catch (const std::exception& e) {
        sendError(res, 500, e.what());
      } catch (...) {
        sendError(res, 500, "internal error");
      }
    });
    const auto page = [this](const httplib::Request& req, httplib::Response& res) {
      std::string body, type;
      if (!webFile(req.path, body, type)) return sendError(res, 404, "no such page: " + req.path);
      res.set_header("Cache-Control", "no-store");
      res.set_header(
          "Content-Security-Policy",
          "default-src 'self'; img-src 'self' blob: data:; style-src 'self'; script-src 'self'; connect-src 'self'");
      res.set_content(body, type.c_str());
    };
    server.Get("/", page);
    server.Get(R"(/[A-Za-z0-9_\-]+\.(js|css|html))", page);
    server.Get("/api/session", [this](const httplib::Request&, httplib::Response& res) {
      const std::lock_guard<std::mutex> lock(mutex);
      sendJson(res, 200, session.session());
    });
    server.Put("/api/labels", [this](const httplib::Request& req, httplib::Response& res) {
      std::size_t frame = 0;
      if (req.has_param("frame")) {
        const std::string f = req.get_param_value("frame");
        const long i = parseIndex(f);
        if (i < 0) return sendError(res, 400, "frame: expected a frame index, got '" + f + "'");
        frame = static_cast<std::size_t>(i);
      }
      if (jsonDepth(req.body) > 64) return sendError(res, 400, "request body: JSON nested deeper than 64 levels");
      nlohmann::json document;
      try {
        document = nlohmann::json::parse(req.body);
      } catch (const nlohmann::json::parse_error& e) {
        return sendError(res, 400, "request body: not JSON (" + std::string(e.what()) + ")");
      }
      const std::lock_guard<std::mutex> lock(mutex);
      if (frame >= session.frameCount())
        return sendError(res, 404,
                         "frame " + std::to_string(frame) + ": the session has " +
                             std::to_string(session.frameCount()) + " frame(s)");
      try {
        sendJson(res, 200, session.putLabels(frame, document));
      } catch (const InputError& e) {
        sendError(res, 400, e.what());
      }
    });
    server.Get("/api/pick", [this](const httplib::Request& req, httplib::Response& res) {
      double at[2] = {0, 0};
      const char* names[2] = {"x", "y"};
      for (int k = 0; k < 2; ++k) {
        const std::string v = req.get_param_value(names[k]);
        char* end = nullptr;
        at[k] = v.empty() || v.size() > 32 ? NAN : std::strtod(v.c_str(), &end);
        if (!std::isfinite(at[k]) || end != v.c_str() + v.size())
          return sendError(res, 400,
                           std::string(names[k]) + ": expected a pixel coordinate, got '" + v.substr(0, 32) + "'");
      }
      const long i = req.has_param("frame") ? parseIndex(req.get_param_value("frame")) : 0;
      const std::lock_guard<std::mutex> lock(mutex);
      if (i < 0 || static_cast<std::size_t>(i) >= session.frameCount()) return sendError(res, 404, "no such frame");
      sendJson(res, 200, session.pick(static_cast<std::size_t>(i), at[0], at[1]));
    });
    server.Post("/api/snap", [this](const httplib::Request& req, httplib::Response& res) {
      if (jsonDepth(req.body) > 64) return sendError(res, 400, "request body: JSON nested deeper than 64 levels");
      nlohmann::json body;
      try {
        body = nlohmann::json::parse(req.body);
      } catch (const nlohmann::json::parse_error& e) {
        return sendError(res, 400, "request body: not JSON (" + std::string(e.what()) + ")");
      }
      if (!body.is_object() || !body.contains("on") || !body["on"].is_boolean())
        return sendError(res, 400, "request body: expected {\"on\": true|false}");
      const std::lock_guard<std::mutex> lock(mutex);
      if (!session.solve()["snap"]["available"].get<bool>())
        return sendError(res, 409, "no robot masks to snap to: start kccd calib label with --masks");
      try {
        sendJson(res, 200, session.setSnap(body["on"].get<bool>()));
      } catch (const InputError& e) {
        sendError(res, 400, e.what());
      }
    });
    server.Post("/api/save", [this](const httplib::Request&, httplib::Response& res) {
      const std::lock_guard<std::mutex> lock(mutex);
      const LabelSaved saved = session.save();
      sendJson(
          res, 200,
          nlohmann::json{{"labels", saved.labels},
                         {"backups", saved.backups},
                         {"camera", saved.camera.empty() ? nlohmann::json(nullptr) : nlohmann::json(saved.camera)}});
    });
    server.Post("/api/quit", [this](const httplib::Request&, httplib::Response& res) {
      sendJson(res, 200, nlohmann::json{{"quitting", true}});
      const std::lock_guard<std::mutex> lock(mutex);
      if (!stopper.joinable())
        stopper = std::thread([this] {
          std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the answer goes out first
          server.stop();
        });
    });
    server.Get(R"(/frame/(\d+)\.png)", [this](const httplib::Request& req, httplib::Response& res) {
      const long i = frameIndex(req);
      const std::lock_guard<std::mutex> lock(mutex);
      if (i < 0 || static_cast<std::size_t>(i) >= session.frameCount()) return sendError(res, 404, "no such frame");
      sendPng(res, session.framePng(static_cast<std::size_t>(i)), true);
    });
    server.Get(R"(/overlay/(\d+)\.png)", [this](const httplib::Request& req, httplib::Response& res) {
      const long i = frameIndex(req);
      const std::lock_guard<std::mutex> lock(mutex);
      if (i < 0 || static_cast<std::size_t>(i) >= session.frameCount()) return sendError(res, 404, "no such frame");
      sendPng(res, session.overlayPng(static_cast<std::size_t>(i)), false);
    });
  }
};

LabelServer::LabelServer(LabelSession& session, LabelServerOptions options)
    : impl_(std::make_unique<Impl>(session, std::move(options))) {
  Impl& s = *impl_;
  if (!s.options.web_root.empty() && !std::filesystem::is_directory(s.options.web_root))
    throw LabelServerError(InputLocation{"--web-root " + s.options.web_root, 0, 0, ""}, "not a folder");
  s.routes();
  const std::string& host = s.options.host;
  if (s.options.port == 0) {
    s.port = s.server.bind_to_any_port(host);
  } else if (s.server.bind_to_port(host, s.options.port)) {
    s.port = s.options.port;
  } else {
    s.port = -1;
  }
  if (s.port <= 0)
    throw LabelServerError(
        InputLocation{"--host " + host, 0, 0, ""},
        "cannot listen on port " + std::to_string(s.options.port) + " (in use, or not an address of this machine)");
  const std::string port = std::to_string(s.port);
  const bool v6 = host.find(':') != std::string::npos;
  s.hosts.insert((v6 ? "[" + host + "]" : host) + ":" + port);
  if (host == "127.0.0.1" || host == "::1") s.hosts.insert("localhost:" + port);
}

LabelServer::~LabelServer() {
  stop();
  if (impl_->stopper.joinable()) impl_->stopper.join();
}

int LabelServer::port() const { return impl_->port; }

std::string LabelServer::url() const { return "http://" + *impl_->hosts.begin() + "/"; }

void LabelServer::run() {
  impl_->started = true;
  if (!impl_->stop_requested) impl_->server.listen_after_bind();
  impl_->finished = true;
}

void LabelServer::stop() {
  impl_->stop_requested = true;
  impl_->server.stop();
  // Not listening yet: run() is about to; stop it once it does.
  while (impl_->started && !impl_->finished) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    impl_->server.stop();
  }
}

void LabelServer::onRequest(std::function<void(const std::string&, const std::string&, int)> log) {
  impl_->log = std::move(log);
}

}  // namespace kccd::overlay
