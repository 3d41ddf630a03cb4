#include "weft/render/camera.h"

#include <cmath>

#include "weft/core/math.h"

namespace weft::render {

ViewAxes viewAxes(const Vec3& forward, const Vec3& up) {
    // Either vector may be sub-normal or huge (scene_file.cpp has checked that
    // they are finite, non-zero and not parallel).
    ViewAxes a;
    a.forward = normalizeAnyLength(forward);
    a.right = normalize(cross(a.forward, normalizeAnyLength(up)));
    a.up = cross(a.right, a.forward);
    return a;
}

FilmExtent filmExtent(double fovDeg, int width, int height) {
    // fov_deg spans the shorter side (pbrt's perspective camera).
    const double half = std::tan(0.5 * radians(fovDeg));
    const double aspect = static_cast<double>(width) / height;
    FilmExtent f;
    f.halfWidth = aspect >= 1 ? half * aspect : half;
    f.halfHeight = aspect >= 1 ? half : half / aspect;
    return f;
}

Camera::Camera(const CameraDesc& desc, int width, int height)
    : origin_(desc.from),
      axes_(viewAxes(desc.to - desc.from, desc.up)),
      film_(filmExtent(desc.fovDeg, width, height)),
      width_(width),
      height_(height) {}

void Camera::ray(double px, double py, Vec3* org, Vec3* dir) const {
    const double x = (2.0 * px / width_ - 1.0) * film_.halfWidth;
    const double y = (1.0 - 2.0 * py / height_) * film_.halfHeight;
    *org = origin_;
    *dir = normalize(axes_.forward + axes_.right * x + axes_.up * y);
}

}  // namespace weft::render
