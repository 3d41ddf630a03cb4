#include "weft/view/view_session.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/json_reader.h"
#include "weft/eval/image_compare.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/yarn/family_model.h"

namespace weft::view {

using nlohmann::json;
namespace fs = std::filesystem;

void ViewOptions::validate() const {
    if (threads < 0 || threads > 1024)
        throw InputError("--threads " + std::to_string(threads) +
                         " is out of range: allowed [0, 1024] (0: all cores)");
    if (!(passSeconds > 0 && passSeconds <= 10))
        throw InputError("pass seconds " + std::to_string(passSeconds) +
                         " is out of range: allowed (0, 10]");
    if (sppCap < 0 || sppCap > kMaxViewSpp)
        throw InputError("--spp " + std::to_string(sppCap) + " is out of range: allowed [1, " +
                         std::to_string(kMaxViewSpp) + "]");
}

std::string presetsDir(const std::string& dir, const std::string& what) {
    std::error_code ec;
    if (!dir.empty()) {
        if (!fs::is_directory(dir, ec)) throw InputError(what + " " + dir + ": not a folder");
        return dir;
    }
    if (const char* env = std::getenv("WEFT_MODELS_DIR"); env && *env) return env;
    return fs::is_directory(WEFT_DEFAULT_MODELS_DIR, ec) ? WEFT_DEFAULT_MODELS_DIR : "";
}

const char* layerName(Layer layer) { return layer == Layer::Neural ? "neural" : "fiber"; }

Layer parseLayer(const std::string& name, const std::string& what) {
    if (name == "neural") return Layer::Neural;
    if (name == "fiber") return Layer::Fiber;
    throw InputError(what + " \"" + name.substr(0, 64) +
                     "\" is not a layer: allowed neural, fiber");
}

// What the worker keeps per layer. The scene, the sums and the keys are the
// worker's alone; the rest is read by other threads under mutex_.
struct ViewSession::LayerState {
    Layer layer;
    std::unique_ptr<render::Scene> scene;
    json geometryKey, coloursKey, viewKey, lightsKey;  // what `scene` was made with
    json accumKey;                                     // the scene JSON whose samples `sum` holds
    std::vector<double> sum;
    int width = 0, height = 0;
    // Bands of rows [bandEdges[b], bandEdges[b + 1]) and the samples each
    // has; `display` is their means (the preview where a band has none).
    std::vector<int> bandEdges;
    std::vector<int64_t> bandSpp;
    Image display;
    double measuredSecondsPerSpp = 0;  // the last pass's (worker only)
    bool draftMaterials = false;       // the scene's materials are drafts (a colour edit)
    // Under mutex_:
    int64_t spp = 0;
    double secondsPerSpp = 0;
    Image mean;
    json shownScene;  // the scene JSON of `mean`
    std::optional<ViewFrame> frame;
};

namespace {

// The model choices: the scene's own models first, then the files given,
// then the presets; each file once, ids its stem made unique.
std::vector<ModelChoice> modelChoices(const render::SceneDesc& desc, const ViewOptions& options) {
    std::vector<std::string> paths;
    for (const render::YarnDesc& y : desc.yarns) paths.push_back(y.model);
    for (const std::string& m : options.models) paths.push_back(fs::absolute(m).string());
    if (!options.presetsDir.empty()) {
        std::error_code ec;
        std::vector<std::string> presets;
        for (const auto& entry : fs::directory_iterator(options.presetsDir, ec))
            if (entry.is_regular_file() && entry.path().extension() == ".json")
                presets.push_back(fs::absolute(entry.path()).string());
        std::sort(presets.begin(), presets.end());
        paths.insert(paths.end(), presets.begin(), presets.end());
    }
    std::vector<ModelChoice> choices;
    std::map<std::string, int> stems;
    for (const std::string& path : paths) {
        const bool seen = std::any_of(choices.begin(), choices.end(), [&](const ModelChoice& c) {
            return sameFilePath(c.path, path);
        });
        if (seen) continue;
        ModelFile file;
        try {
            file = ModelFile::load(path);
        } catch (const InputError& e) {
            // A preset folder may hold other JSON files (its README's examples).
            if (!options.presetsDir.empty() &&
                path.rfind(fs::absolute(options.presetsDir).string(), 0) == 0)
                continue;
            throw;
        }
        ModelChoice c;
        c.path = path;
        const std::string stem = fs::path(path).stem().string();
        const int n = ++stems[stem];
        c.id = n == 1 ? stem : stem + "-" + std::to_string(n);
        if (file.family) {
            c.colour = true;
            c.family = file.family->box;
            c.centre = file.family->centre();
        } else {
            c.colour = file.single && file.single->colour.has_value();
            if (c.colour && file.single->appearance) {
                const AppearanceTable& t = *file.single->appearance;
                c.reach = std::make_pair(Rgb(t.darkest(0), t.darkest(1), t.darkest(2)),
                                         Rgb(t.brightest(0), t.brightest(1), t.brightest(2)));
            }
        }
        choices.push_back(std::move(c));
    }
    return choices;
}

// A light at `strength` times its scene's emission (sky, envmap: "scale";
// sphere, constant: "radiance"; point: "intensity"; directional: "irradiance").
json scaledLight(const json& light, double strength, const std::string& what) {
    json out = light;
    const std::string type = light.value("type", "");
    if (type == "sky" || type == "envmap") {
        out["scale"] = light.value("scale", 1.0) * strength;
        return out;
    }
    for (const char* key : {"radiance", "intensity", "irradiance"}) {
        if (!light.contains(key) || !light[key].is_array()) continue;
        for (auto& v : out[key]) v = v.get<double>() * strength;
        return out;
    }
    throw InputError(what + ": a " + type + " light has no strength to change");
}

json srgbJson(const Rgb& linear) {
    const Rgb s = linearToSrgb(linear);
    return {s.r, s.g, s.b};
}

// The appearance `value` ([r, g, b] sRGB) moved into the model's reach, a
// little inside it (the table's end nodes are exact only to rounding); a
// note when it moved. Other forms are left to the scene's parser.
json appearanceInReach(const json& value, const ModelChoice& model, const std::string& what,
                       std::vector<std::string>* notes) {
    if (!model.reach || !value.is_array() || value.size() != 3) return value;
    json out = value;
    bool moved = false;
    for (int c = 0; c < 3; ++c) {
        if (!value[c].is_number()) return value;
        const double v = value[c].get<double>();
        if (!std::isfinite(v) || v < 0 || v > 1) return value;
        const double lo = model.reach->first[c] * 1.002, hi = model.reach->second[c] * 0.998;
        const double linear = srgbToLinear(v);
        if (linear < lo || linear > hi) {
            out[c] = linearToSrgb(std::clamp(linear, lo, hi));
            moved = true;
        }
    }
    if (moved) {
        char text[160];
        std::snprintf(text, sizeof text, "%s: the nearest colour %s shows, sRGB (%.3f, %.3f, %.3f)",
                      what.c_str(), model.id.c_str(), out[0].get<double>(), out[1].get<double>(),
                      out[2].get<double>());
        notes->push_back(text);
    }
    return out;
}

// The parts of a scene JSON that each need a different update. A yarn's
// colour is not its geometry (Scene::setYarnColours) unless a yarn of the
// scene is vertex-coloured.
bool vertexColoured(const json& scene) {
    for (const json& y : scene.at("yarns"))
        if (y.contains("vertex_colours")) return true;
    return false;
}
constexpr const char* kColourKeys[] = {"colour", "appearance"};
json geometryOf(const json& scene) {
    json yarns = scene.at("yarns");
    if (!vertexColoured(scene))
        for (json& y : yarns)
            for (const char* k : kColourKeys) y.erase(k);
    return {yarns, scene.contains("objects") ? scene["objects"] : json()};
}
json coloursOf(const json& scene) {
    json colours = json::array();
    for (const json& y : scene.at("yarns")) {
        json c = json::object();
        for (const char* k : kColourKeys)
            if (y.contains(k)) c[k] = y[k];
        colours.push_back(c);
    }
    return colours;
}
json viewOf(const json& scene) { return {scene.at("camera"), scene.at("film")}; }

// "<dir>/view-NNNN" with the first NNNN for which none of the three files exists.
std::string freshViewName(const std::string& dir) {
    for (int n = 1; n <= 99999; ++n) {
        char name[32];
        std::snprintf(name, sizeof name, "view-%04d", n);
        const fs::path base = fs::path(dir) / name;
        bool taken = false;
        for (const char* ext : {".json", ".exr", ".png"}) {
            std::error_code ec;
            if (fs::exists(base.string() + ext, ec) || ec) taken = true;
        }
        if (!taken) return base.string();
    }
    throw InputError(dir + ": holds view-0001 ... view-99999 already: choose another --out");
}

}  // namespace

ViewSession::ViewSession(const ViewOptions& options) : options_(options) {
    options_.validate();
    render::SceneDesc desc = render::loadScene(options_.scenePath);
    if (render::isAnimated(desc)) {
        const int first = desc.animation.hasRange() ? desc.animation.first : 0;
        desc = render::sceneAtFrame(desc, first, first,
                                    desc.animation.hasRange() ? desc.animation.last : first);
    }
    sceneName_ = options_.scenePath;
    baseDir_ = desc.baseDir;
    choices_ = modelChoices(desc, options_);
    scene_ = render::toJson(desc);
    scene_.erase("animation");
    // The view draws every yarn in neural mode (the fiber layer overrides it):
    // saved scenes say so, so that weft render draws what the view showed.
    for (json& y : scene_["yarns"]) y["mode"] = "neural";
    if (scene_["lights"].empty())
        scene_["lights"] = json::array({{{"type", "sky"}, {"scale", 1.0}}});
    baseLights_ = scene_["lights"];
    strengths_.assign(baseLights_.size(), 1.0);
    desc_ = render::parseScene(scene_, sceneName_, baseDir_);
    sppCap_ = options_.sppCap > 0 ? options_.sppCap : std::min(desc_.render.spp, kMaxViewSpp);
    if (desc_.film.width < kMinViewSide || desc_.film.height < kMinViewSide ||
        desc_.film.width > kMaxViewSide || desc_.film.height > kMaxViewSide)
        throw InputError(sceneName_ + ": film " + std::to_string(desc_.film.width) + " x " +
                         std::to_string(desc_.film.height) + ": weft view shows sides in [" +
                         std::to_string(kMinViewSide) + ", " + std::to_string(kMaxViewSide) + "]");
    lastGood_ = {scene_, strengths_};

    // The neural scene now: a scene that does not build is an error at start.
    neural_ = std::make_unique<LayerState>();
    neural_->layer = Layer::Neural;
    render::SceneOptions sceneOptions;
    sceneOptions.mode = "neural";
    neural_->scene = std::make_unique<render::Scene>(desc_, sceneOptions);
    neural_->geometryKey = geometryOf(scene_);
    neural_->coloursKey = coloursOf(scene_);
    neural_->viewKey = viewOf(scene_);
    neural_->lightsKey = scene_["lights"];
    fiber_ = std::make_unique<LayerState>();
    fiber_->layer = Layer::Fiber;
    lastClient_ = std::chrono::steady_clock::now();
    worker_ = std::thread([this] { run(); });
}

ViewSession::~ViewSession() { stop(); }

void ViewSession::stop() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
        ++generation_;
    }
    workChanged_.notify_all();
    frameReady_.notify_all();
    if (worker_.joinable()) worker_.join();
}

void ViewSession::touch() {
    bool wake = false;
    {
        std::lock_guard lock(mutex_);
        const auto now = std::chrono::steady_clock::now();
        const double since = std::chrono::duration<double>(now - lastClient_).count();
        wake = since > 0.5;
        // A page that (re)appears loads first, with the cores to itself: the
        // view it is shown is there already.
        if (!options_.renderWithoutClient && since > kClientGoneSeconds)
            resumeAt_ = now + std::chrono::milliseconds(kResumeDelayMs);
        lastClient_ = now;
    }
    if (wake) workChanged_.notify_all();
}

const ModelChoice* ViewSession::choiceOf(const std::string& path) const {
    for (const ModelChoice& c : choices_)
        if (c.path == path) return &c;
    return nullptr;
}

json ViewSession::state() const {
    std::lock_guard lock(mutex_);
    json lights = json::array();
    for (size_t i = 0; i < baseLights_.size(); ++i)
        lights.push_back({{"type", baseLights_[i]["type"]}, {"strength", strengths_[i]}});
    json yarns = json::array();
    for (const json& y : scene_["yarns"]) {
        const ModelChoice* model = choiceOf(y["model"].get<std::string>());
        yarns.push_back({{"model", model ? model->id : std::string()},
                         {"colour", y.contains("colour") ? y["colour"] : json()},
                         {"appearance", y.contains("appearance") ? y["appearance"] : json()},
                         {"vertex_colours", y.contains("vertex_colours")},
                         {"yarn", y.contains("yarn") ? y["yarn"] : json()}});
    }
    json models = json::array();
    for (const ModelChoice& c : choices_)
        models.push_back({{"id", c.id},
                          {"colour", c.colour},
                          {"family", c.family ? c.family->toJson() : json()},
                          {"centre", c.centre ? c.centre->toJson() : json()},
                          {"reach", c.reach ? json{{"darkest", srgbJson(c.reach->first)},
                                                   {"brightest", srgbJson(c.reach->second)}}
                                            : json()}});
    return {{"generation", generation_},
            {"scene_name", fs::path(sceneName_).filename().string()},
            {"camera", scene_["camera"]},
            {"film", scene_["film"]},
            {"spp_cap", sppCap_},
            {"exposure", exposure_},
            {"ab", ab_},
            {"lights", std::move(lights)},
            {"yarns", std::move(yarns)},
            {"models", std::move(models)},
            {"can_save", !options_.outDir.empty()}};
}

json ViewSession::applyEdit(const json& edit) {
    const std::lock_guard editLock(editMutex_);
    std::vector<std::string> notes;
    json next;
    std::vector<double> strengths;
    int cap;
    double exposure;
    bool ab;
    {
        std::lock_guard lock(mutex_);
        next = scene_;
        strengths = strengths_;
        cap = sppCap_;
        exposure = exposure_;
        ab = ab_;
    }
    JsonObjectReader r(edit, "edit");
    r.allowKeys({"camera", "film", "spp_cap", "exposure", "ab", "lights", "yarns"});
    if (r.has("camera")) {
        const JsonObjectReader c = r.object("camera", {"from", "to", "up", "fov_deg"});
        // Their values are the scene's to check (parseScene below).
        for (const char* k : {"from", "to", "up", "fov_deg"})
            if (c.has(k)) next["camera"][k] = c.value(k);
    }
    if (r.has("film")) {
        const JsonObjectReader f = r.object("film", {"width", "height"});
        for (const char* k : {"width", "height"})
            if (f.has(k)) next["film"][k] = f.integer(k, {kMinViewSide, kMaxViewSide});
    }
    if (r.has("spp_cap")) cap = static_cast<int>(r.integer("spp_cap", {1, kMaxViewSpp}));
    if (r.has("exposure"))
        exposure = r.number("exposure", NumberRange::closed(-64, 64).with("stops"));
    if (r.has("ab")) ab = r.boolean("ab");
    if (r.has("lights")) {
        for (JsonObjectReader& l : r.objects("lights")) {
            l.allowKeys({"index", "strength"});
            const auto i = static_cast<size_t>(
                l.integer("index", {0, static_cast<int64_t>(strengths.size()) - 1}));
            strengths[i] = l.number("strength", NumberRange::closed(0, 1000));
        }
    }
    for (size_t i = 0; i < strengths.size(); ++i)
        next["lights"][i] =
            scaledLight(baseLights_[i], strengths[i], "edit: lights[" + std::to_string(i) + "]");
    if (r.has("yarns")) {
        for (JsonObjectReader& e : r.objects("yarns")) {
            e.allowKeys({"index", "model", "appearance", "colour", "yarn"});
            const auto i = static_cast<size_t>(
                e.integer("index", {0, static_cast<int64_t>(next["yarns"].size()) - 1}));
            json& y = next["yarns"][i];
            if (e.has("model")) {
                const std::string id = e.string("model");
                auto c = std::find_if(choices_.begin(), choices_.end(),
                                      [&](const ModelChoice& m) { return m.id == id; });
                if (c == choices_.end()) {
                    std::string ids;
                    for (const ModelChoice& m : choices_) ids += (ids.empty() ? "" : ", ") + m.id;
                    e.fail("model", "\"" + id.substr(0, 64) +
                                        "\" is not one of the models weft view offers: " + ids);
                }
                y["model"] = c->path;
                // What the new model takes: a family model a yarn (its centre
                // until the page gives one), any other none; a colour only
                // where the model takes one.
                if (c->family) {
                    if (!y.contains("yarn")) y["yarn"] = c->centre->toJson();
                    // Colour by appearance would need the appearance table of
                    // every yarn a slider makes (seconds each): a family
                    // model's yarn takes its fiber colour (C_TT) instead.
                    y.erase("appearance");
                } else {
                    y.erase("yarn");
                }
                if (!c->colour) y.erase("colour"), y.erase("appearance");
            }
            const ModelChoice* model = choiceOf(y["model"].get<std::string>());
            for (const char* k : {"appearance", "colour"}) {
                if (!e.has(k)) continue;
                if (e.isNull(k)) {
                    y.erase(k);
                    continue;
                }
                // Its form and range are the scene's to check (parseScene below).
                y[k] = std::string(k) == "appearance" && model
                           ? appearanceInReach(e.value(k), *model, "edit: " + e.pathOf(k), &notes)
                           : e.value(k);
                // One colour at a time: the one just given.
                y.erase(std::string(k) == "colour" ? "appearance" : "colour");
                y.erase("vertex_colours");
            }
            if (e.has("yarn")) {
                // Checked against the model's box here, so that a slider
                // beyond it is refused at once rather than by a failed build.
                if (model && model->family)
                    model->family->check(
                        YarnPoint::fromJson(e.value("yarn"), "edit", e.pathOf("yarn")),
                        "edit: " + e.pathOf("yarn"));
                y["yarn"] = e.value("yarn");
            }
        }
    }
    // The whole scene, as weft render would check it.
    render::SceneDesc desc = render::parseScene(next, sceneName_, baseDir_);
    uint64_t generation;
    {
        std::lock_guard lock(mutex_);
        const bool sceneChanged = next != scene_;
        scene_ = std::move(next);
        desc_ = std::move(desc);
        strengths_ = std::move(strengths);
        sppCap_ = cap;
        if (exposure != exposure_) reencode_ = true;
        exposure_ = exposure;
        ab_ = ab;
        if (sceneChanged) error_.clear();
        generation = ++generation_;
    }
    workChanged_.notify_all();
    frameReady_.notify_all();
    return {{"generation", generation}, {"notes", notes}};
}

std::optional<ViewFrame> ViewSession::frame(Layer layer, uint64_t after,
                                            std::chrono::milliseconds wait) {
    touch();
    std::unique_lock lock(mutex_);
    const LayerState& l = layer == Layer::Neural ? *neural_ : *fiber_;
    frameReady_.wait_for(lock, wait,
                         [&] { return stopping_ || (l.frame && l.frame->seq > after); });
    if (l.frame && l.frame->seq > after) return l.frame;
    return std::nullopt;
}

json ViewSession::stats() const {
    std::lock_guard lock(mutex_);
    auto layerJson = [&](const LayerState& l) -> json {
        if (!l.frame) return json();
        return {{"spp", l.spp},
                {"seconds_per_spp", l.secondsPerSpp},
                {"width", l.mean.width},
                {"height", l.mean.height}};
    };
    const bool done = neural_->spp >= sppCap_ && neural_->shownScene == scene_ &&
                      (!ab_ || (fiber_->spp >= sppCap_ && fiber_->shownScene == scene_));
    const bool idle =
        !options_.renderWithoutClient &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - lastClient_).count() >
            kClientGoneSeconds;
    return {{"generation", generation_},
            {"status", building_ ? "building"
                       : done    ? "done"
                       : idle    ? "idle"
                                 : "rendering"},
            {"error", error_.empty() ? json() : json(error_)},
            {"neural", layerJson(*neural_)},
            {"fiber", ab_ ? layerJson(*fiber_) : json()},
            {"ssim", ab_ && ssim_ ? json(*ssim_) : json()}};
}

json ViewSession::sceneJson() const {
    std::lock_guard lock(mutex_);
    json scene = neural_->shownScene.is_null() ? scene_ : neural_->shownScene;
    if (neural_->spp > 0) scene["render"]["spp"] = neural_->spp;
    return scene;
}

json ViewSession::save() {
    if (options_.outDir.empty())
        throw InputError("weft view was started without an out folder: nothing is saved");
    Image image;
    json scene;
    int64_t spp;
    double exposure;
    {
        std::lock_guard lock(mutex_);
        if (neural_->spp == 0) throw InputError("nothing is rendered yet: save again in a moment");
        image = neural_->mean;
        scene = neural_->shownScene;
        spp = neural_->spp;
        exposure = exposure_;
    }
    scene["render"]["spp"] = spp;
    std::error_code ec;
    fs::create_directories(options_.outDir, ec);
    if (ec) throw InputError("cannot create " + options_.outDir + ": " + ec.message());
    const std::string base = freshViewName(options_.outDir);
    const render::SceneDesc desc = render::parseScene(scene, sceneName_, baseDir_);
    checkOutputsSpareInputs(render::sceneInputs(desc, options_.scenePath),
                            {{"the saved scene", base + ".json"},
                             {"the saved EXR", base + ".exr"},
                             {"the saved PNG", base + ".png"}});
    writeExr(base + ".exr", image);
    writePng(base + ".png", image, exposure);
    writeFileAtomic(base + ".json", scene.dump(2) + "\n");
    const std::string name = fs::path(base).filename().string();
    return {{"dir", options_.outDir},
            {"scene", name + ".json"},
            {"exr", name + ".exr"},
            {"png", name + ".png"},
            {"spp", spp}};
}

bool ViewSession::workLeft() const {
    if (reencode_) return true;
    if (std::chrono::steady_clock::now() < resumeAt_) return false;
    const bool watched =
        options_.renderWithoutClient ||
        std::chrono::duration<double>(std::chrono::steady_clock::now() - lastClient_).count() <=
            kClientGoneSeconds;
    if (!watched) return false;
    auto left = [&](const LayerState& l) { return l.accumKey != scene_ || l.spp < sppCap_; };
    return left(*neural_) || (ab_ && left(*fiber_));
}

void ViewSession::updateSsim() {
    ssim_.reset();
    const Image& a = neural_->mean;
    const Image& b = fiber_->mean;
    if (!ab_ || neural_->spp == 0 || fiber_->spp == 0 || a.width != b.width ||
        a.height != b.height || a.width < 11 || a.height < 11 ||
        neural_->shownScene != fiber_->shownScene)
        return;
    ssim_ = eval::compareImages(a, "neural", b, "fiber", {}).ssim;
}

void ViewSession::run() {
    std::unique_lock lock(mutex_);
    while (true) {
        auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
        if (resumeAt_ > std::chrono::steady_clock::now()) until = std::min(until, resumeAt_);
        workChanged_.wait_until(lock, until, [&] { return stopping_ || workLeft(); });
        if (stopping_) return;
        if (!workLeft()) continue;
        if (reencode_) {
            reencode_ = false;
            for (LayerState* l : {neural_.get(), fiber_.get()}) {
                if (!l->frame || l->mean.width == 0) continue;
                l->frame->jpeg = encodeJpeg(l->mean, exposure_);
                l->frame->seq = ++seq_;
                l->frame->generation = generation_;
            }
            frameReady_.notify_all();
            continue;
        }
        // The layer behind: the neural one first, then the one with fewer samples.
        LayerState* layer = neural_.get();
        if (ab_) {
            const bool neuralLeft = neural_->accumKey != scene_ || neural_->spp < sppCap_;
            const bool fiberStale = fiber_->accumKey != scene_;
            if (neural_->accumKey == scene_ &&
                (fiberStale || (fiber_->spp < neural_->spp) || !neuralLeft))
                layer = fiber_.get();
        }
        const json key = scene_;
        const render::SceneDesc desc = desc_;
        const uint64_t generation = generation_;
        lock.unlock();
        renderPass(*layer, desc, generation, key);
        lock.lock();
    }
}

void ViewSession::renderPass(LayerState& layer, const render::SceneDesc& desc, uint64_t generation,
                             const json& key) {
    // The page's status says "building" while `build` runs (an exception
    // clears it below).
    const auto whileBuilding = [&](const auto& build) {
        {
            std::lock_guard lock(mutex_);
            building_ = true;
        }
        build();
        std::lock_guard lock(mutex_);
        building_ = false;
    };
    // The scene up to date with `key`.
    try {
        const json geometry = geometryOf(key);
        if (!layer.scene || layer.geometryKey != geometry)
            whileBuilding([&] {
                render::SceneOptions sceneOptions;
                sceneOptions.mode = layerName(layer.layer);
                layer.scene.reset();  // the old one's memory first (a fiber scene is large)
                layer.scene = std::make_unique<render::Scene>(desc, sceneOptions);
                layer.geometryKey = geometry;
                layer.coloursKey = coloursOf(key);
                layer.viewKey = viewOf(key);
                layer.lightsKey = key["lights"];
                layer.draftMaterials = false;
            });
        if (layer.coloursKey != coloursOf(key))
            // A colour alone: its materials, not the geometry (a 256 px
            // knit's geometry is about 15 ms of the 130 ms a colour costs),
            // and drafts at first (the neural BSDF without its sampling
            // table, about half of its build): the first look below shows
            // them, the samples that accumulate are the final materials'.
            whileBuilding([&] {
                const bool draft = layer.layer == Layer::Neural;
                layer.scene->setYarnColours(desc, draft);
                layer.coloursKey = coloursOf(key);
                layer.draftMaterials = draft;
            });
        if (layer.viewKey != viewOf(key)) {
            layer.scene->setView(desc);
            layer.viewKey = viewOf(key);
        }
        if (layer.lightsKey != key["lights"]) {
            layer.scene->setLights(desc);
            layer.lightsKey = key["lights"];
        }
    } catch (const std::exception& e) {
        // Back to the last scene that built; the page shows the error.
        std::lock_guard lock(mutex_);
        building_ = false;
        if (layer.geometryKey != geometryOf(key)) layer.scene.reset();
        error_ = e.what();
        if (scene_ == key) {
            scene_ = lastGood_[0];
            strengths_ = lastGood_[1].get<std::vector<double>>();
            desc_ = render::parseScene(scene_, sceneName_, baseDir_);
            ++generation_;
        }
        frameReady_.notify_all();
        return;
    }
    const bool fresh = layer.accumKey != key;
    if (fresh) {
        layer.accumKey = key;
        layer.width = desc.film.width;
        layer.height = desc.film.height;
        layer.sum.assign(static_cast<size_t>(layer.width) * layer.height * 3, 0.0);
        // Bands of whole tile rows, as many as make one sample of a band take
        // about kViewPassSeconds (by this layer's last time per sample), so
        // that a slow sample still refines the page several times a second.
        const int tileRows = (layer.height + render::kRenderTile - 1) / render::kRenderTile;
        const int bands = std::clamp(
            static_cast<int>(std::ceil(layer.measuredSecondsPerSpp / options_.passSeconds)), 1,
            tileRows);
        layer.bandEdges.clear();
        for (int b = 0; b <= bands; ++b)
            layer.bandEdges.push_back(
                std::min(layer.height, tileRows * b / bands * render::kRenderTile));
        layer.bandSpp.assign(static_cast<size_t>(bands), 0);
        layer.display = Image(layer.width, layer.height);
        std::lock_guard lock(mutex_);
        layer.spp = 0;
        if (layer.layer == Layer::Neural && key != lastGood_[0]) lastGood_ = {key, strengths_};
    }
    int64_t cap;
    double exposure;
    {
        std::lock_guard lock(mutex_);
        cap = sppCap_;
        exposure = exposure_;
    }
    const int bands = static_cast<int>(layer.bandSpp.size());
    std::atomic<bool> cancelled{false};
    render::RenderOptions ro;
    ro.threads = options_.threads;
    ro.seed = desc.render.seed;
    ro.sampler = desc.render.sampler;
    ro.maxDepth = desc.render.maxDepth;
    ro.quiet = true;
    ro.stopRequested = [&] {
        if (cancelled.load(std::memory_order_relaxed)) return true;
        std::lock_guard lock(mutex_);
        if (stopping_ || generation_ != generation) cancelled = true;
        return cancelled.load();
    };
    // A low-resolution first look while the full image's first sample is
    // traced, where that sample is slow (a camera drag then answers at once);
    // it stands for the bands not traced yet.
    // Draft materials are shown that way too, never accumulated.
    const bool preview = layer.bandSpp == std::vector<int64_t>(bands, 0) &&
                         (layer.measuredSecondsPerSpp > 0.04 || layer.draftMaterials) &&
                         layer.width >= 64 && layer.height >= 64;
    if (preview) {
        int factor = 2;
        while (factor < 8 &&
               layer.measuredSecondsPerSpp / (factor * factor) > kViewPreviewSeconds &&
               std::min(layer.width, layer.height) / (2 * factor) >= 16)
            factor *= 2;
        render::SceneDesc coarse = desc;
        coarse.film = {layer.width / factor, layer.height / factor};
        layer.scene->setView(coarse);
        ro.spp = 1;
        ro.samples = {0, 1};
        render::RenderResult small;
        try {
            small = render::render(*layer.scene, ro);
        } catch (...) {
            layer.scene->setView(desc);
            throw;
        }
        layer.scene->setView(desc);
        if (small.stats.partial) return;
        for (int y = 0; y < layer.height; ++y)
            for (int x = 0; x < layer.width; ++x)
                layer.display.set(x, y,
                                  small.image.get(std::min(x / factor, small.image.width - 1),
                                                  std::min(y / factor, small.image.height - 1)));
        const std::string jpeg = encodeJpeg(small.image, exposure);
        std::lock_guard lock(mutex_);
        layer.frame = ViewFrame{++seq_,
                                generation,
                                jpeg,
                                small.image.width,
                                small.image.height,
                                0,
                                small.stats.secondsPerSpp * factor * factor};
        frameReady_.notify_all();
    }
    if (layer.draftMaterials) {
        whileBuilding([&] { layer.scene->finishMaterials(); });
        layer.draftMaterials = false;
    }
    // The band behind; it catches up with the others, or (all equal) takes
    // as many samples as fit in a pass.
    const int b = static_cast<int>(std::min_element(layer.bandSpp.begin(), layer.bandSpp.end()) -
                                   layer.bandSpp.begin());
    const int64_t have = layer.bandSpp[static_cast<size_t>(b)];
    const int64_t leader = *std::max_element(layer.bandSpp.begin(), layer.bandSpp.end());
    const double bandSecondsPerSpp = layer.measuredSecondsPerSpp / bands;
    const int64_t n =
        leader > have ? leader - have
        : have == 0
            ? 1
            : std::clamp<int64_t>(static_cast<int64_t>(std::floor(
                                      options_.passSeconds / std::max(bandSecondsPerSpp, 1e-6))),
                                  1, std::max<int64_t>(cap - have, 1));
    ro.spp = static_cast<int>(have + n);
    ro.samples = {have, have + n};
    if (bands > 1) ro.rows = {layer.bandEdges[b], layer.bandEdges[b + 1]};
    const render::RenderResult r = render::render(*layer.scene, ro);
    if (r.stats.partial) return;  // an edit came: its scene is next
    // The whole image's time per sample, from the band's.
    const double secondsPerSpp =
        r.stats.secondsPerSpp * layer.height / (layer.bandEdges[b + 1] - layer.bandEdges[b]);
    layer.measuredSecondsPerSpp = secondsPerSpp;
    layer.bandSpp[static_cast<size_t>(b)] += n;
    const double total = static_cast<double>(have + n);
    for (int y = layer.bandEdges[b]; y < layer.bandEdges[b + 1]; ++y)
        for (size_t i = 3 * static_cast<size_t>(y) * layer.width;
             i < 3 * static_cast<size_t>(y + 1) * layer.width; ++i) {
            layer.sum[i] += static_cast<double>(r.image.pixels[i]) * static_cast<double>(n);
            layer.display.pixels[i] = static_cast<float>(layer.sum[i] / total);
        }
    const int64_t complete = *std::min_element(layer.bandSpp.begin(), layer.bandSpp.end());
    const bool round = complete == *std::max_element(layer.bandSpp.begin(), layer.bandSpp.end());
    const std::string jpeg = encodeJpeg(layer.display, exposure);
    std::lock_guard lock(mutex_);
    layer.secondsPerSpp = secondsPerSpp;
    // What Save and the SSIM take: every band at the same samples.
    if (round) {
        layer.spp = complete;
        layer.mean = layer.display;
        layer.shownScene = key;
        updateSsim();
    }
    layer.frame =
        ViewFrame{++seq_, generation, jpeg, layer.width, layer.height, complete, secondsPerSpp};
    frameReady_.notify_all();
}

}  // namespace weft::view
