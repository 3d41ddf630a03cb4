// Tests of weft view (issue 44): the progressive view is the spp render of
// the same scene, edits are validated and atomic, a colour edit moves the
// colour, and the server refuses hostile requests while it keeps serving.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/test_util.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/view/view_server.h"
#include "weft/view/view_session.h"

namespace weft::view {
namespace {

using nlohmann::json;
using weft::testing::expectInputError;

const std::string kColourModel =
    std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-colour-small.json";
const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

class ViewTest : public weft::testing::TempDirTest {
  protected:
    // Two short yarns side by side under the sky and a sphere light.
    std::string writeScene(int side = 24, int spp = 6) {
        writeFileAtomic(path("yarn.txt"),
                        "-0.25 -0.05 0\n0.25 -0.05 0\n\n-0.25 0.05 0\n0.25 0.05 0\n");
        const json scene = {
            {"camera",
             {{"from", {0, 0, 1}}, {"to", {0, 0, 0}}, {"up", {0, 1, 0}}, {"fov_deg", 20}}},
            {"film", {{"width", side}, {"height", side}}},
            {"render", {{"spp", spp}, {"seed", 7}}},
            {"lights",
             {{{"type", "sky"}, {"scale", 1.0}},
              {{"type", "sphere"},
               {"center", {0.5, 0.5, 1}},
               {"radius", 0.2},
               {"radiance", {4, 4, 4}}}}},
            {"yarns",
             {{{"curves", "yarn.txt"},
               {"radius", 0.04},
               {"plies", 2},
               {"ply_twist", 0.3},
               {"model", kColourModel},
               {"colour", {0.5, 0.5, 0.5}}}}}};
        writeFileAtomic(path("scene.json"), scene.dump());
        return path("scene.json");
    }

    // The saved scene rendered at its spp, as weft render would, is the saved
    // image: the view's samples were [0, 1), [1, n), ... of the same pixels
    // and seed, with the same materials.
    void expectSavedIsTheSppRender(const json& saved) {
        const render::SceneDesc desc =
            render::loadScene(path("out/" + saved["scene"].get<std::string>()));
        EXPECT_EQ(desc.render.spp, saved["spp"].get<int>());
        const render::Scene built(desc);
        render::RenderOptions ro;
        ro.spp = desc.render.spp;
        ro.seed = desc.render.seed;
        ro.threads = 1;
        ro.quiet = true;
        const Image reference = render::render(built, ro).image;
        const Image view = readImage(path("out/" + saved["exr"].get<std::string>()));
        ASSERT_EQ(view.pixels.size(), reference.pixels.size());
        double largest = 0, sum = 0;
        for (size_t i = 0; i < view.pixels.size(); ++i) {
            largest = std::max(largest, std::abs(double(view.pixels[i]) - reference.pixels[i]) /
                                            (1e-3 + std::abs(double(reference.pixels[i]))));
            sum += reference.pixels[i];
        }
        EXPECT_GT(sum, 0.0);
        EXPECT_LT(largest, 1e-4);
    }

    ViewOptions options(const std::string& scene) {
        ViewOptions o;
        o.scenePath = scene;
        o.models = {kFleece, std::string(WEFT_SOURCE_DIR) + "/models/family.json"};
        o.outDir = path("out");
        o.threads = 2;
        o.renderWithoutClient = true;
        return o;
    }
};

// Frames until the neural layer reaches `spp` samples (or 120 s pass).
ViewFrame waitForSpp(ViewSession& session, int64_t spp, uint64_t generation = 0) {
    ViewFrame last;
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (std::chrono::steady_clock::now() < end) {
        auto f = session.frame(Layer::Neural, last.seq, std::chrono::milliseconds(500));
        if (!f) continue;
        last = *f;
        if (last.generation >= generation && last.spp >= spp) return last;
    }
    ADD_FAILURE() << "no frame with " << spp << " spp";
    return last;
}

TEST_F(ViewTest, ProgressiveViewIsTheSppRenderOfTheSavedScene) {
    const std::string scene = writeScene();
    ViewSession session(options(scene));
    const ViewFrame frame = waitForSpp(session, 6);
    EXPECT_EQ(frame.spp, 6);
    EXPECT_EQ(frame.width, 24);
    // A JPEG: SOI marker first, EOI last.
    ASSERT_GE(frame.jpeg.size(), 4u);
    EXPECT_EQ(static_cast<unsigned char>(frame.jpeg[0]), 0xFF);
    EXPECT_EQ(static_cast<unsigned char>(frame.jpeg[1]), 0xD8);

    const json saved = session.save();
    EXPECT_EQ(saved["scene"], "view-0001.json");
    EXPECT_EQ(saved["spp"], 6);
    expectSavedIsTheSppRender(saved);
    // A second save clobbers nothing.
    writeFileAtomic(path("out/view-0002.png"), "taken");
    EXPECT_EQ(session.save()["scene"], "view-0003.json");
}

// A pass far shorter than a sample: the view traces bands of rows (one per
// tile row) in turn, and what it saves is still the spp render.
TEST_F(ViewTest, BandsOfRowsAddUpToTheSppRender) {
    ViewOptions o = options(writeScene(40, 5));
    o.passSeconds = 1e-5;
    ViewSession session(o);
    waitForSpp(session, 5);
    // The next view is traced in bands (the time per sample is known now).
    const uint64_t g =
        session.applyEdit({{"lights", {{{"index", 0}, {"strength", 0.8}}}}})["generation"];
    const ViewFrame frame = waitForSpp(session, 5, g);
    EXPECT_EQ(frame.spp, 5);
    const json saved = session.save();
    const render::SceneDesc desc =
        render::loadScene(path("out/" + saved["scene"].get<std::string>()));
    EXPECT_EQ(desc.lights.size(), 2u);
    render::RenderOptions ro;
    ro.spp = 5;
    ro.seed = desc.render.seed;
    ro.quiet = true;
    const Image reference = render::render(render::Scene(desc), ro).image;
    const Image view = readImage(path("out/" + saved["exr"].get<std::string>()));
    double largest = 0;
    for (size_t i = 0; i < view.pixels.size(); ++i)
        largest = std::max(largest, std::abs(double(view.pixels[i]) - reference.pixels[i]) /
                                        (1e-3 + std::abs(double(reference.pixels[i]))));
    EXPECT_LT(largest, 1e-4);
    o.passSeconds = 0;
    expectInputError([&] { ViewSession s(o); }, {"pass seconds", "(0, 10]"});
}

TEST_F(ViewTest, EditsAreValidatedAndLeaveTheStateAsItWasWhenRefused) {
    ViewSession session(options(writeScene()));
    const json before = session.state();
    EXPECT_EQ(before["lights"].size(), 2u);
    // The models the page may choose: the scene's and the one given, by id.
    ASSERT_EQ(before["models"].size(), 3u);
    EXPECT_EQ(before["models"][0]["id"], "fleece-colour-small");
    EXPECT_EQ(before["models"][0]["colour"], true);
    EXPECT_EQ(before["models"][1]["id"], "fleece-small");
    const std::vector<std::pair<json, std::vector<std::string>>> refused = {
        {json::array(), {"edit: expected an object"}},
        {{{"colour", 1}}, {"edit: unknown key \"colour\"", "allowed: camera"}},
        {{{"film", {{"width", 5}}}}, {"edit: film.width = 5", "[16, 2048]"}},
        {{{"film", {{"width", "wide"}}}}, {"edit: film.width: expected an integer in [16, 2048]"}},
        {{{"spp_cap", 0}}, {"edit: spp_cap = 0", "[1, 65536]"}},
        {{{"exposure", 100}}, {"edit: exposure = 100", "[-64, 64]"}},
        {{{"ab", 1}}, {"edit: ab: expected true or false"}},
        {{{"lights", {{{"index", 2}, {"strength", 1}}}}}, {"edit: lights[0].index = 2", "[0, 1]"}},
        {{{"lights", {{{"index", 0}, {"strength", -1}}}}},
         {"edit: lights[0].strength = -1", "[0, 1000]"}},
        {{{"lights", {{{"index", 0}}}}}, {"edit: lights[0]: missing key \"strength\""}},
        {{{"yarns", {{{"index", 0}, {"model", "../../etc/passwd"}}}}},
         {"edit: yarns[0].model: \"../../etc/passwd\" is not one of the models", "fleece-small"}},
        {{{"yarns", {{{"index", 0}, {"model", kFleece}}}}}, {"is not one of the models"}},
        {{{"yarns", {{{"index", 0}, {"colour", {1, 2}}}}}}, {"yarns[0].colour"}},
        {{{"yarns", {{{"index", 0}, {"colour", {0.5, 0.5, 1.5}}}}}}, {"yarns[0].colour"}},
        {{{"camera", {{"from", {0, 0, 0}}}}}, {"camera"}},
        {{{"camera", {{"fov_deg", 180}}}}, {"fov_deg"}},
        {{{"camera", {{"lens", 50}}}}, {"edit: camera: unknown key \"lens\""}},
    };
    for (const auto& [edit, parts] : refused) {
        SCOPED_TRACE(edit.dump());
        try {
            session.applyEdit(edit);
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            for (const std::string& p : parts)
                EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
        }
        EXPECT_EQ(session.state(), before);
    }
    // Accepted: the light's strength scales its radiance in the scene shown.
    const uint64_t g = session.applyEdit({{"lights", {{{"index", 1}, {"strength", 0.5}}}},
                                          {"spp_cap", 2},
                                          {"exposure", 1}})["generation"];
    EXPECT_GT(g, before["generation"].get<uint64_t>());
    const json after = session.state();
    EXPECT_EQ(after["lights"][1]["strength"], 0.5);
    EXPECT_EQ(after["spp_cap"], 2);
    waitForSpp(session, 2, g);
    const json shown = session.sceneJson();
    EXPECT_EQ(shown["lights"][1]["radiance"], json({2.0, 2.0, 2.0}));
    EXPECT_EQ(shown["lights"][0]["scale"], 1.0);
    // An appearance beyond the colour model's reach: the nearest colour it
    // shows (inside its table's darkest and brightest), with a note.
    const json reach = session.state()["models"][0]["reach"];
    ASSERT_FALSE(reach.is_null());
    const double darkestGreen = reach["darkest"][1];
    const json moved =
        session.applyEdit({{"yarns", {{{"index", 0}, {"appearance", {0.5, 0.0, 0.5}}}}}});
    ASSERT_EQ(moved["notes"].size(), 1u) << moved.dump();
    EXPECT_NE(
        moved["notes"][0].get<std::string>().find("edit: yarns[0].appearance: the nearest colour"),
        std::string::npos);
    const json appearance = session.state()["yarns"][0]["appearance"];
    EXPECT_EQ(appearance[0], 0.5);
    EXPECT_GT(appearance[1].get<double>(), darkestGreen);
    EXPECT_LT(appearance[1].get<double>(), darkestGreen + 0.01);
    EXPECT_EQ(session.state()["yarns"][0]["colour"], json());  // one colour at a time
    waitForSpp(session, 2, moved["generation"]);
    EXPECT_EQ(session.stats()["error"], json()) << session.stats().dump();
    // A family model: its box's centre, no appearance, and a yarn outside
    // its box refused at once.
    session.applyEdit({{"yarns", {{{"index", 0}, {"model", "family"}}}}});
    json family = session.state()["yarns"][0];
    EXPECT_EQ(family["model"], "family");
    EXPECT_EQ(family["appearance"], json());
    EXPECT_EQ(family["yarn"]["fibers"], 400);
    json yarn = family["yarn"];
    yarn["fibers"] = 3000;
    expectInputError(
        [&] {
            session.applyEdit({{"yarns", {{{"index", 0}, {"yarn", yarn}}}}});
        },
        {"edit: yarns[0].yarn", "fibers", "3000", "[200, 600]"});
    EXPECT_EQ(session.state()["yarns"][0]["yarn"]["fibers"], 400);
    // A model without colour drops the yarn's colour.
    session.applyEdit({{"yarns", {{{"index", 0}, {"model", "fleece-small"}}}}});
    EXPECT_EQ(session.state()["yarns"][0]["colour"], json());
    EXPECT_EQ(session.state()["yarns"][0]["model"], "fleece-small");
}

// The mean of the pixels whose luminance is above the sky-free background's:
// the yarn's, by channel.
Rgb yarnMean(const Image& image) {
    double sum[3] = {0, 0, 0};
    int n = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            // The yarns cross the middle rows of the image.
            if (std::abs(y - image.height / 2) > image.height / 8) continue;
            const Rgb c = image.get(x, y);
            for (int k = 0; k < 3; ++k) sum[k] += c[k];
            ++n;
        }
    return Rgb(sum[0] / n, sum[1] / n, sum[2] / n);
}

TEST_F(ViewTest, AColourEditMovesTheYarnsColourThatWay) {
    ViewSession session(options(writeScene(32, 4)));
    session.applyEdit({{"spp_cap", 4}});
    auto meanAt = [&](const Rgb& colour) {
        const uint64_t g = session.applyEdit(
            {{"yarns",
              {{{"index", 0}, {"colour", {colour.r, colour.g, colour.b}}}}}})["generation"];
        waitForSpp(session, 4, g);
        const json saved = session.save();
        return yarnMean(readImage(path("out/" + saved["exr"].get<std::string>())));
    };
    const Rgb red = meanAt(Rgb(0.9, 0.2, 0.2));
    const Rgb blue = meanAt(Rgb(0.2, 0.2, 0.9));
    EXPECT_GT(red.r / red.b, 1.5 * blue.r / blue.b)
        << "red " << red.r << " " << red.b << ", blue " << blue.r << " " << blue.b;
}

// At 64 px a colour edit's first look is shown with draft materials
// (docs/view.md); the samples the view then accumulates and saves are the
// final materials', as weft render's: also after edits that came before a
// draft was finished.
TEST_F(ViewTest, AfterAColourEditTheSavedImageIsTheSppRender) {
    ViewSession session(options(writeScene(64, 3)));
    session.applyEdit({{"spp_cap", 3}});
    uint64_t g = 0;
    for (const Rgb& colour : {Rgb(0.9, 0.2, 0.2), Rgb(0.3, 0.8, 0.2), Rgb(0.2, 0.2, 0.9)})
        g = session.applyEdit(
            {{"yarns",
              {{{"index", 0}, {"colour", {colour.r, colour.g, colour.b}}}}}})["generation"];
    waitForSpp(session, 3, g);
    expectSavedIsTheSppRender(session.save());
    g = session.applyEdit({{"yarns", {{{"index", 0}, {"colour", {0.6, 0.6, 0.3}}}}}})["generation"];
    waitForSpp(session, 3, g);
    expectSavedIsTheSppRender(session.save());
}

TEST_F(ViewTest, AbRendersTheFibersAndComparesThem) {
    ViewSession session(options(writeScene(24, 2)));
    const uint64_t g = session.applyEdit({{"ab", true}, {"spp_cap", 2}})["generation"];
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(240);
    json stats;
    while (std::chrono::steady_clock::now() < end) {
        stats = session.stats();
        if (stats["status"] == "done" && !stats["ssim"].is_null()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ASSERT_FALSE(stats["fiber"].is_null()) << stats.dump();
    EXPECT_EQ(stats["fiber"]["spp"], 2);
    EXPECT_GT(stats["fiber"]["seconds_per_spp"].get<double>(), 0.0);
    ASSERT_FALSE(stats["ssim"].is_null()) << stats.dump();
    EXPECT_GT(stats["ssim"].get<double>(), 0.0);
    EXPECT_LE(stats["ssim"].get<double>(), 1.0);
    auto fiber = session.frame(Layer::Fiber, 0, std::chrono::milliseconds(0));
    ASSERT_TRUE(fiber.has_value());
    EXPECT_GE(fiber->generation, g);
}

TEST_F(ViewTest, SaveNeedsAnOutFolderAndAnImage) {
    ViewOptions o = options(writeScene());
    o.outDir.clear();
    ViewSession session(o);
    expectInputError([&] { session.save(); }, {"without an out folder"});
    EXPECT_EQ(session.state()["can_save"], false);
}

TEST_F(ViewTest, OptionsAndScenesOutsideTheViewsLimitsAreRefused) {
    ViewOptions o = options(writeScene(8));
    expectInputError([&] { ViewSession s(o); }, {"scene.json", "film 8 x 8", "[16, 2048]"});
    o = options(writeScene());
    o.sppCap = -1;
    expectInputError([&] { ViewSession s(o); }, {"--spp -1"});
    o = options(path("missing.json"));
    expectInputError([&] { ViewSession s(o); }, {"missing.json"});
    ServerOptions server;
    server.port = 70000;
    expectInputError([&] { server.validate(); }, {"--port 70000", "[0, 65535]"});
    EXPECT_TRUE(ServerOptions{}.loopback());
    ServerOptions any;
    any.host = "0.0.0.0";
    EXPECT_FALSE(any.loopback());
}

// Sends raw bytes to the server and returns what comes back before it closes
// (or `readBack` is false: closes at once, a client that vanished).
std::string rawRequest(int port, const std::string& bytes, bool readBack = true) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::string reply;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
        (void)!::write(fd, bytes.data(), bytes.size());
        if (readBack) {
            char buffer[4096];
            ssize_t n;
            while ((n = ::read(fd, buffer, sizeof buffer)) > 0) reply.append(buffer, n);
        }
    }
    ::close(fd);
    return reply;
}

TEST_F(ViewTest, TheServerRefusesHostileRequestsAndKeepsServing) {
    ViewSession session(options(writeScene()));
    ViewServer server(session, ServerOptions{});
    ASSERT_GT(server.port(), 0);
    EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");
    httplib::Client client("127.0.0.1", server.port());
    client.set_read_timeout(10, 0);

    auto page = client.Get("/");
    ASSERT_TRUE(page);
    EXPECT_EQ(page->status, 200);
    EXPECT_NE(page->body.find("<script src=\"/view.js\">"), std::string::npos);
    // Nothing from elsewhere: no absolute http(s) URL in the page's files.
    size_t count = 0;
    const PageFile* files = pageFiles(&count);
    for (size_t i = 0; i < count; ++i) {
        EXPECT_EQ(std::string(files[i].body).find("http://"), std::string::npos) << files[i].path;
        EXPECT_EQ(std::string(files[i].body).find("https://"), std::string::npos) << files[i].path;
        auto got = client.Get(files[i].path);
        ASSERT_TRUE(got);
        EXPECT_EQ(got->status, 200) << files[i].path;
    }

    // A frame: a JPEG with its samples in the headers.
    auto frame = client.Get("/api/frame?layer=neural&after=0");
    ASSERT_TRUE(frame);
    ASSERT_EQ(frame->status, 200);
    EXPECT_EQ(frame->get_header_value("Content-Type"), "image/jpeg");
    EXPECT_FALSE(frame->get_header_value("X-Weft-Seq").empty());

    auto expectStatus = [&](const httplib::Result& r, int status, const std::string& part) {
        ASSERT_TRUE(r);
        EXPECT_EQ(r->status, status) << r->body;
        if (!part.empty()) {
            EXPECT_NE(r->body.find(part), std::string::npos) << r->body;
        }
    };
    // Paths out of the page: none reaches a file.
    const std::string port = std::to_string(server.port());
    for (const std::string target : {"/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd",
                                     "/view.js/../../../etc/passwd", "/api/../../etc/passwd"}) {
        const std::string reply =
            rawRequest(server.port(), "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1:" + port +
                                          "\r\nConnection: close\r\n\r\n");
        EXPECT_EQ(reply.find("root:"), std::string::npos) << target;
        EXPECT_NE(reply.find(" 404 "), std::string::npos) << target << ": " << reply.substr(0, 80);
    }
    expectStatus(client.Post("/api/edit", "{\"camera\": ", "application/json"), 400,
                 "malformed JSON");
    expectStatus(client.Post("/api/edit", std::string(5000, '[') + std::string(5000, ']'),
                             "application/json"),
                 400, "nest");
    expectStatus(client.Post("/api/edit", "{\"film\": {\"width\": 1e9}}", "application/json"), 400,
                 "edit: film.width");
    expectStatus(client.Post("/api/edit", "\"\\ud800\"", "application/json"), 400, "");
    expectStatus(client.Post("/api/edit", std::string(100000, ' '), "application/json"), 413, "");
    expectStatus(client.Get("/api/frame?layer=../x"), 400, "not a layer");
    expectStatus(client.Get("/api/frame?after=-1"), 400, "frame number");
    expectStatus(client.Get("/api/frame?after=99999999999999999999"), 400, "frame number");
    // DNS rebinding: another host name is refused.
    expectStatus(client.Get("/api/state", {{"Host", "attacker.example:" + port}}), 403, "Host");

    // Clients that vanish: half a request, a frame request closed at once.
    rawRequest(server.port(),
               "POST /api/edit HTTP/1.1\r\nHost: 127.0.0.1:" + port +
                   "\r\nContent-Length: 1000\r\n\r\n{\"ab\"",
               false);
    for (int i = 0; i < 8; ++i)
        rawRequest(server.port(),
                   "GET /api/frame?after=999999 HTTP/1.1\r\nHost: 127.0.0.1:" + port + "\r\n\r\n",
                   false);
    // Many clients at once.
    std::atomic<int> ok{0};
    std::vector<std::thread> clients;
    for (int i = 0; i < 24; ++i)
        clients.emplace_back([&, i] {
            httplib::Client c("127.0.0.1", server.port());
            c.set_read_timeout(20, 0);
            auto r = i % 2 ? c.Get("/api/state") : c.Get("/api/frame?after=0");
            if (r && r->status == 200) ++ok;
        });
    for (std::thread& t : clients) t.join();
    EXPECT_EQ(ok.load(), 24);

    // Still serving, edits and all.
    expectStatus(client.Post("/api/edit", "{\"spp_cap\": 3}", "application/json"), 200,
                 "generation");
    auto state = client.Get("/api/state");
    ASSERT_TRUE(state);
    EXPECT_EQ(json::parse(state->body)["spp_cap"], 3);
    auto saved = client.Post("/api/save", "", "application/json");
    ASSERT_TRUE(saved);
    EXPECT_EQ(saved->status, 200) << saved->body;
    server.stop();
    session.stop();
}

}  // namespace
}  // namespace weft::view
