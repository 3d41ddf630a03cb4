// weft/render/camera.h — the pinhole camera of a scene and its view geometry.
//
// A pinhole at `from` looking at `to`, `up` projected to the image's
// vertical, fov_deg the full angle of the shorter image side (pbrt's
// perspective camera); pixel (x, y) covers [x, x+1) x [y, y+1) with y = 0 at
// the top. viewAxes and filmExtent are the one definition of that geometry:
// the renderer's Camera and the scene generator's framing and light
// placement (eval/scene_gen.cpp) both use them.
#pragma once

#include "weft/core/vec.h"
#include "weft/render/scene_file.h"

namespace weft::render {

// The view axes of a camera looking along `forward` (any length): forward
// normalised, right = normalize(forward x up), up' = right x forward (up
// projected to the image's vertical; `up` must not be parallel to forward).
struct ViewAxes {
    Vec3 forward, right, up;
};
ViewAxes viewAxes(const Vec3& forward, const Vec3& up);

// Half-width and half-height of the image plane at distance 1 for a
// width x height film whose shorter side spans fovDeg degrees.
struct FilmExtent {
    double halfWidth = 0, halfHeight = 0;
};
FilmExtent filmExtent(double fovDeg, int width, int height);

class Camera {
  public:
    Camera() = default;
    Camera(const CameraDesc& desc, int width, int height);
    // Primary ray through film position (px, py), px in [0, width), py in [0, height).
    void ray(double px, double py, Vec3* org, Vec3* dir) const;

  private:
    Vec3 origin_;
    ViewAxes axes_;
    FilmExtent film_;  // of the image plane at distance 1
    int width_ = 1, height_ = 1;
};

}  // namespace weft::render
