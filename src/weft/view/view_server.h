// weft/view/view_server.h — the HTTP server of `weft view` (issue 44, docs/view.md).
//
// cpp-httplib (Debian's libcpp-httplib-dev; docs/view.md says why) serves
// the page (plain HTML, JavaScript and CSS compiled into weft: nothing from
// elsewhere) and a small JSON API over one ViewSession:
//   GET  /api/state                      the state and the choices (ViewSession::state)
//   POST /api/edit                       an edit (ViewSession::applyEdit); 400 + {"error"}
//   GET  /api/frame?layer=L&after=SEQ    the newest JPEG of layer L newer than SEQ,
//                                        waiting up to kFrameWaitMs (204 if none)
//   GET  /api/stats                      samples, time per sample, SSIM, errors
//   POST /api/save                       ViewSession::save
// Nothing is read from the file system on a client's request, so no path a
// client sends can reach a file. Requests are bounded (kMaxMessageBytes), a
// Host header that is not the address served is refused (DNS rebinding), a
// malformed message gets a 400 with the reason and the server keeps serving.
#pragma once

#include <memory>
#include <string>
#include <thread>

#include "weft/view/view_session.h"

namespace httplib {
class Server;
}

namespace weft::view {

inline constexpr size_t kMaxMessageBytes = 64 * 1024;
inline constexpr int kFrameWaitMs = 1000;
// Frame requests waiting at once beyond which one is answered at once.
inline constexpr int kMaxWaitingFrames = 16;

struct ServerOptions {
    std::string host = "127.0.0.1";
    int port = 0;  // 0: any free port

    // InputError naming --port ([0, 65535]) or --bind (non-empty, at most 253 characters).
    void validate() const;
    // Whether `host` is a loopback address (127.0.0.0/8, ::1, localhost).
    bool loopback() const;
};

class ViewServer {
  public:
    // Binds (InputError naming the address when it cannot) and serves on a
    // thread of its own until stop() or destruction.
    ViewServer(ViewSession& session, const ServerOptions& options);
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    int port() const { return port_; }
    std::string url() const;  // "http://HOST:PORT/"
    void stop();

  private:
    ViewSession& session_;
    ServerOptions options_;
    int port_ = 0;
    std::unique_ptr<httplib::Server> server_;
    std::thread thread_;
};

// The page's files, compiled in (view_page.cpp, made by CMake from page/).
struct PageFile {
    const char* path;  // "/index.html"
    const char* contentType;
    const char* body;
};
const PageFile* pageFiles(size_t* count);

}  // namespace weft::view
