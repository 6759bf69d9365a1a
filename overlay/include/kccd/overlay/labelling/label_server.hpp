// The local web server of `kccd calib label`: one page and a JSON API over a LabelSession, on a
// loopback address. It takes no file path from any request, answers only requests addressed to
// the host it is bound to (DNS rebinding), refuses writes from another origin or not sent as JSON
// (cross-site forms), and bounds every request's size.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "kccd/input_error.hpp"
#include "kccd/overlay/labelling/label_session.hpp"

namespace kccd::overlay {

/// The server cannot start (the address cannot be bound, the web root is not a folder).
class LabelServerError : public InputError {
 public:
  using InputError::InputError;
};

/// Where and how the server listens.
struct LabelServerOptions {
  std::string host = "127.0.0.1";           ///< the address bound (loopback unless asked otherwise)
  int port = 0;                             ///< 0: any free port
  std::size_t max_request_bytes = 1 << 20;  ///< a larger request body is refused (413)
  std::string web_root;                     ///< serve the page's files from this folder instead of the built-in ones
};

/// The server. GET / (the page), GET /app.js, /app.css and the page's modules; GET /api/session;
/// PUT /api/labels[?frame=N]; POST /api/save; POST /api/quit; GET /frame/N.png; GET /overlay/N.png.
class LabelServer {
 public:
  /// Binds the address; throws LabelServerError when it cannot.
  LabelServer(LabelSession& session, LabelServerOptions options);
  ~LabelServer();
  LabelServer(const LabelServer&) = delete;
  LabelServer& operator=(const LabelServer&) = delete;

  int port() const;         ///< the port bound
  std::string url() const;  ///< "http://HOST:PORT/"
  /// Serves until stop() or POST /api/quit; returns then. Call once.
  void run();
  /// Ends run() (from any thread, also a signal handler's helper thread).
  void stop();
  /// Called (on a server thread) after each accepted request with its method, path and status.
  void onRequest(std::function<void(const std::string&, const std::string&, int)> log);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The page's built-in file at `path` ("/" is "index.html"), or nullptr; `type` gets its MIME type.
const std::string* builtinWebFile(const std::string& path, std::string& type);

}  // namespace kccd::overlay
