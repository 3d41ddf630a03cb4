// weft/view/view_session.h — what `weft view` shows (issue 44, docs/view.md).
//
// A ViewSession holds a scene being looked at and edited, and one worker
// thread that renders it progressively: passes of consecutive samples
// [s, s + n) of every pixel (RenderOptions::samples), accumulated as their
// sample-weighted mean, so that the view after S samples is the image of
// `weft render --spp S` on the same scene and seed (up to float rounding).
// Each pass is sized to take about kViewPassSeconds, so the page refines a
// few times a second; an edit restarts the accumulation at once, cancelling
// the pass in flight (stopRequested between tiles).
//
// The state is the scene's JSON (render/scene_file.h, toJson): an edit (the
// page's message, applyEdit below) changes a copy, parseScene validates the
// whole scene, and only then does the session take it. Changing the camera
// or the film only moves the camera (Scene::setView), the lights only
// rebuilds them (Scene::setLights); a yarn's model, colour or family
// parameters build the scene again. A build that fails (an appearance out of
// a model's reach, say) puts back the last scene that built and reports the
// error.
//
// Two layers: "neural" (every yarn in neural mode, always) and, with A/B on,
// "fiber" (every fiber, the ground truth), rendered in turn so that both
// stay at about the same samples per pixel, with the SSIM between them.
//
// Models are chosen by id from a list the session announces (the shipped
// presets, the model files given to weft view, the scene's own), never by a
// path from the page.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/core/image.h"
#include "weft/render/scene_file.h"

namespace weft::view {

// The pass the session aims for: long enough that the tiles that finish last
// cost little, short enough for several refinements a second.
inline constexpr double kViewPassSeconds = 0.15;
// About how long the low-resolution first look of a view may take: its
// pixels are 2, 4 or 8 image pixels a side, the fewest that keep it this
// short (a 256 x 256 knit on 2 cores: 4).
inline constexpr double kViewPreviewSeconds = 0.03;
// A client that has not asked for a frame for this long has gone: the
// session stops rendering until one asks again.
inline constexpr double kClientGoneSeconds = 3.0;
// A client that comes back after that: rendering resumes this much later,
// leaving the cores to the page while it loads.
inline constexpr int kResumeDelayMs = 250;
// Limits of what the page may ask for.
inline constexpr int kMinViewSide = 16, kMaxViewSide = 2048;
inline constexpr int kMaxViewSpp = 65536;

struct ViewOptions {
    std::string scenePath;
    // Model files offered besides the scene's own and the presets.
    std::vector<std::string> models;
    // The shipped presets (models/*.json); "" offers none.
    std::string presetsDir;
    // Where Save writes; "" refuses to save.
    std::string outDir;
    int threads = 0;                        // 0: all cores
    int sppCap = 0;                         // 0: the scene's render.spp
    double passSeconds = kViewPassSeconds;  // the pass the worker aims for, (0, 10]
    // Whether the session should render when no client has asked recently
    // (tests and benchmarks that read frames without a page).
    bool renderWithoutClient = false;

    // InputError naming the flag (threads in [0, 1024], sppCap in [0,
    // kMaxViewSpp], passSeconds in (0, 10]).
    void validate() const;
};

// The folder of preset models: `dir` when given (InputError naming `what`
// unless it is a folder), else $WEFT_MODELS_DIR, else the models/ of the
// source tree weft was built from while it is there, else "" (none).
std::string presetsDir(const std::string& dir, const std::string& what);

// A model the page may choose.
struct ModelChoice {
    std::string id;                   // the file's stem, made unique ("fleece", "fleece-2")
    std::string path;                 // resolved; never sent to the page
    bool colour = false;              // takes a colour (any-colour or family model)
    std::optional<FamilyBox> family;  // a family model's box
    std::optional<YarnPoint> centre;  // and the yarn at its centre
    // A colour model's appearance table's reach, linear per channel: the
    // darkest and the brightest colour it shows.
    std::optional<std::pair<Rgb, Rgb>> reach;
};

enum class Layer { Neural, Fiber };
const char* layerName(Layer layer);
// "neural" or "fiber"; InputError naming `what` otherwise.
Layer parseLayer(const std::string& name, const std::string& what);

// One encoded image of a layer.
struct ViewFrame {
    uint64_t seq = 0;         // grows with every frame of the session (any layer)
    uint64_t generation = 0;  // the edit it shows
    std::string jpeg;
    int width = 0, height = 0;
    int64_t spp = 0;  // 0: a low-resolution preview of the first sample
    double secondsPerSpp = 0;
};

class ViewSession {
  public:
    // Loads the scene (an animated scene at its first frame) and the model
    // choices and starts the worker; InputError naming the file or flag.
    explicit ViewSession(const ViewOptions& options);
    ~ViewSession();
    ViewSession(const ViewSession&) = delete;
    ViewSession& operator=(const ViewSession&) = delete;

    // {"generation", "scene_name", "camera", "film", "spp_cap", "exposure",
    // "ab", "lights": [{"type", "strength"}], "yarns": [{"model", "colour",
    // "appearance", "yarn"}], "models": [{"id", "colour", "family": box or
    // null, "centre", "reach": {"darkest", "brightest"} (sRGB) or null}],
    // "can_save"}.
    nlohmann::json state() const;

    // Applies the page's edit (docs/view.md, "Messages"): an object with any
    // of "camera", "film", "spp_cap", "exposure", "ab", "lights", "yarns".
    // InputError naming the field and its allowed range (and the state is
    // unchanged) for anything else. An appearance beyond a colour model's
    // reach is moved to the nearest colour it shows, with a note. Returns
    // {"generation": the new generation, "notes": [...]}.
    nlohmann::json applyEdit(const nlohmann::json& edit);

    // The newest frame of `layer` if its seq is greater than `after`, waiting
    // up to `wait` for one; none when there is none by then.
    std::optional<ViewFrame> frame(Layer layer, uint64_t after, std::chrono::milliseconds wait);

    // {"generation", "status": "rendering" | "done" | "building" | "idle",
    // "error" (the last edit's build error, or null), "neural" and "fiber":
    // {"spp", "seconds_per_spp", "width", "height"} or null, "ssim" (between
    // the two layers at their current samples, or null)}.
    nlohmann::json stats() const;

    // Writes the neural view: VIEW.json (the scene as shown, render.spp the
    // samples so far), VIEW.exr and VIEW.png (at the view's exposure) into the
    // out folder, VIEW = "view-NNNN" with the first NNNN that clobbers
    // nothing. InputError when there is no out folder, nothing rendered yet,
    // or an output would replace an input. Returns {"scene", "exr", "png",
    // "spp"} (names inside the out folder) and "dir".
    nlohmann::json save();

    // The scene as the view shows it now (render.spp the neural samples so far).
    nlohmann::json sceneJson() const;

    // A client asked for something: render (again) if it had stopped for
    // want of one.
    void touch();

    // Stops the worker (also on destruction); frame() returns at once after.
    void stop();

  private:
    struct LayerState;
    void run();
    bool workLeft() const;  // with mutex_ held
    // The choice of a model file (as the scene JSON holds it), or none.
    const ModelChoice* choiceOf(const std::string& path) const;
    void renderPass(LayerState& layer, const render::SceneDesc& desc, uint64_t generation,
                    const nlohmann::json& key);
    void updateSsim();  // with mutex_ held

    ViewOptions options_;
    std::string sceneName_;
    std::string baseDir_;  // the scene's relative paths resolve against it
    std::vector<ModelChoice> choices_;
    nlohmann::json baseLights_;  // the scene's lights at strength 1

    std::mutex editMutex_;  // one edit at a time (each starts from the last)
    mutable std::mutex mutex_;
    std::condition_variable workChanged_, frameReady_;
    nlohmann::json scene_;  // the scene's JSON now (lights at their strengths)
    render::SceneDesc desc_;
    nlohmann::json lastGood_;  // the last scene JSON that built
    std::vector<double> strengths_;
    int sppCap_ = 64;
    double exposure_ = 0;
    bool ab_ = false;
    uint64_t generation_ = 0;
    uint64_t seq_ = 0;
    std::string error_;
    bool building_ = false;
    bool stopping_ = false;
    bool reencode_ = false;
    std::chrono::steady_clock::time_point lastClient_, resumeAt_;
    std::optional<double> ssim_;
    std::unique_ptr<LayerState> neural_, fiber_;
    std::thread worker_;
};

}  // namespace weft::view
