#include "weft/view/view_server.h"

#include <httplib.h>

#include <atomic>
#include <cstdio>
#include <string_view>

#include "weft/core/error.h"
#include "weft/core/json_file.h"

namespace weft::view {

using nlohmann::json;

void ServerOptions::validate() const {
    if (port < 0 || port > 65535)
        throw InputError("--port " + std::to_string(port) +
                         " is out of range: allowed [0, 65535] (0: any free port)");
    if (host.empty() || host.size() > 253)
        throw InputError("--bind: give an address or host name (at most 253 characters)");
}

bool ServerOptions::loopback() const {
    return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

namespace {

void sendJson(httplib::Response& res, const json& body, int status = 200) {
    res.status = status;
    res.set_header("Cache-Control", "no-store");
    res.set_content(body.dump(), "application/json");
}

void sendError(httplib::Response& res, int status, const std::string& message) {
    sendJson(res, {{"error", message}}, status);
}

// A JSON body within the limits (the server's payload limit answers 413 before this).
json bodyJson(const httplib::Request& req) {
    if (req.body.size() > kMaxMessageBytes)
        throw InputError("message of " + std::to_string(req.body.size()) +
                         " bytes: allowed at most " + std::to_string(kMaxMessageBytes));
    return parseJsonText(req.body.empty() ? std::string_view("{}") : std::string_view(req.body),
                         "message");
}

}  // namespace

ViewServer::ViewServer(ViewSession& session, const ServerOptions& options)
    : session_(session), options_(options), server_(std::make_unique<httplib::Server>()) {
    options_.validate();
    httplib::Server& s = *server_;
    // Long-polling frame requests hold a thread each for up to kFrameWaitMs;
    // a browser opens at most 6 connections to one host.
    s.new_task_queue = [] { return new httplib::ThreadPool(32); };
    s.set_payload_max_length(kMaxMessageBytes);
    s.set_read_timeout(2, 0);
    s.set_write_timeout(5, 0);
    s.set_keep_alive_timeout(2);
    s.set_tcp_nodelay(true);

    const bool checkHost = options_.loopback();
    s.set_pre_routing_handler(
        [this, checkHost](const httplib::Request& req, httplib::Response& res) {
            // DNS rebinding: a page from elsewhere that names our port under its
            // own host name is refused.
            if (checkHost) {
                const std::string host = req.get_header_value("Host");
                const size_t colon = host.rfind(':');
                const std::string name = host.substr(0, colon);
                const bool ok = colon != std::string::npos &&
                                host.substr(colon + 1) == std::to_string(port_) &&
                                (name == "127.0.0.1" || name == "localhost" || name == "[::1]" ||
                                 name == options_.host);
                if (!ok) {
                    sendError(res, 403, "Host \"" + host.substr(0, 64) + "\" is not this server");
                    return httplib::Server::HandlerResponse::Handled;
                }
            }
            return httplib::Server::HandlerResponse::Unhandled;
        });
    s.set_exception_handler(
        [](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
            try {
                std::rethrow_exception(ep);
            } catch (const InputError& e) {
                sendError(res, 400, e.what());
            } catch (const std::exception& e) {
                sendError(res, 500, e.what());
            } catch (...) {
                sendError(res, 500, "unknown error");
            }
        });
    s.set_error_handler([](const httplib::Request&, httplib::Response& res) {
        if (res.body.empty()) {
            res.set_header("Cache-Control", "no-store");
            res.set_content("{\"error\":\"" + std::to_string(res.status) + "\"}",
                            "application/json");
        }
    });

    size_t count = 0;
    const PageFile* files = pageFiles(&count);
    for (size_t i = 0; i < count; ++i) {
        const PageFile f = files[i];
        auto serve = [f](const httplib::Request&, httplib::Response& res) {
            res.set_header("Cache-Control", "no-store");
            res.set_header("Content-Security-Policy",
                           "default-src 'self'; img-src 'self' blob: data:; style-src 'self'");
            res.set_content(f.body, f.contentType);
        };
        s.Get(f.path, serve);
        if (std::string_view(f.path) == "/index.html") s.Get("/", serve);
    }

    s.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
        session_.touch();
        sendJson(res, session_.state());
    });
    s.Get("/api/stats", [this](const httplib::Request&, httplib::Response& res) {
        sendJson(res, session_.stats());
    });
    s.Post("/api/edit", [this](const httplib::Request& req, httplib::Response& res) {
        sendJson(res, session_.applyEdit(bodyJson(req)));
    });
    s.Post("/api/save", [this](const httplib::Request& req, httplib::Response& res) {
        bodyJson(req);  // well-formed, even if empty
        sendJson(res, session_.save());
    });
    auto waiting = std::make_shared<std::atomic<int>>(0);
    s.Get("/api/frame", [this, waiting](const httplib::Request& req, httplib::Response& res) {
        const Layer layer =
            parseLayer(req.has_param("layer") ? req.get_param_value("layer") : "neural", "layer");
        uint64_t after = 0;
        if (req.has_param("after")) {
            const std::string text = req.get_param_value("after");
            if (text.empty() || text.size() > 19 ||
                text.find_first_not_of("0123456789") != std::string::npos)
                throw InputError("after \"" + text.substr(0, 32) +
                                 "\" must be a frame number (0 to 10^19)");
            after = std::stoull(text);
        }
        const int already = waiting->fetch_add(1);
        const auto wait =
            std::chrono::milliseconds(already >= kMaxWaitingFrames ? 0 : kFrameWaitMs);
        std::optional<ViewFrame> frame;
        try {
            frame = session_.frame(layer, after, wait);
        } catch (...) {
            waiting->fetch_sub(1);
            throw;
        }
        waiting->fetch_sub(1);
        res.set_header("Cache-Control", "no-store");
        if (!frame) {
            res.status = 204;
            return;
        }
        res.set_header("X-Weft-Seq", std::to_string(frame->seq));
        res.set_header("X-Weft-Generation", std::to_string(frame->generation));
        res.set_header("X-Weft-Spp", std::to_string(frame->spp));
        res.set_header("X-Weft-Width", std::to_string(frame->width));
        res.set_header("X-Weft-Height", std::to_string(frame->height));
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, "%.6g", frame->secondsPerSpp);
        res.set_header("X-Weft-Seconds-Per-Spp", seconds);
        res.set_content(std::move(frame->jpeg), "image/jpeg");
    });

    port_ = options_.port == 0
                ? s.bind_to_any_port(options_.host)
                : (s.bind_to_port(options_.host, options_.port) ? options_.port : -1);
    if (port_ <= 0)
        throw InputError("cannot listen on " + options_.host + ":" + std::to_string(options_.port) +
                         " (in use, or not an address of this machine): choose another --port "
                         "or --bind");
    thread_ = std::thread([this] { server_->listen_after_bind(); });
}

ViewServer::~ViewServer() { stop(); }

void ViewServer::stop() {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
}

std::string ViewServer::url() const {
    const bool v6 = options_.host.find(':') != std::string::npos;
    return "http://" + (v6 ? "[" + options_.host + "]" : options_.host) + ":" +
           std::to_string(port_) + "/";
}

}  // namespace weft::view
