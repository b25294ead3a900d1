// Blender's camera model: sensor fit, focal length, shift, orthographic scale and clipping planes
// (BKE_camera_params_compute_viewplane), looking down local -Z with +Y up; Cycles' thin lens
// (depth of field: circular or polygonal aperture, anamorphic ratio) and its panoramic projections
// (equirectangular, fisheye equidistant, equisolid and lens polynomial, mirror ball, equiangular
// cubemap face; kernel/camera/camera.h and projection.h).
#pragma once

#include <vector>

#include "core/math.h"
#include "core/sampling.h"
#include "geometry/motion.h"

namespace lt {

enum class PanoramaType {
  Equirectangular = 0,
  FisheyeEquidistant = 1,
  FisheyeEquisolid = 2,
  MirrorBall = 3,
  FisheyeLensPolynomial = 4,
  EquiangularCubemapFace = 5
};

struct CameraDesc {
  bool orthographic = false;
  bool panorama = false;
  Transform xf;
  float focal_length = 50, sensor_width = 36, sensor_height = 24;
  int sensor_fit = 0;  // 0 auto, 1 horizontal, 2 vertical
  float ortho_scale = 7.3f;
  float shift_x = 0, shift_y = 0;
  float clip_start = 0.1f, clip_end = 1000;
  float pixel_aspect = 1;
  // Depth of field: the aperture's radius in scene units (0: a pinhole), the distance of the plane
  // in focus along the view axis, the aperture's blades (< 3: a disk) and their rotation
  // (radians), and the anamorphic ratio (the aperture's x is divided by it).
  float aperture_radius = 0, focus_distance = 10;
  int aperture_blades = 0;
  float aperture_rotation = 0, aperture_ratio = 1;
  // Panoramas (Cycles' camera settings): the projection, the fisheyes' field of view (radians)
  // and the equisolid's lens (mm), the equirectangular's latitude and longitude ranges (radians).
  PanoramaType panorama_type = PanoramaType::FisheyeEquisolid;
  float fisheye_fov = kPi, fisheye_lens = 10.5f;
  float latitude_min = -0.5f * kPi, latitude_max = 0.5f * kPi, longitude_min = -kPi, longitude_max = kPi;
  // The lens polynomial's k0 .. k4: the angle from the axis at sensor radius r (mm) is
  // -(k0 + k1 r + ... + k4 r^4) (Cycles' fisheye_lens_polynomial_to_direction; Cycles' defaults).
  // A viewport looking through the camera: the film's u range and v range on the frame's
  // [0, 1]^2 (before the shift; an empty range: the frame itself), and the frame's aspect ratio
  // for the fisheyes' sensor fit (0: the film's).
  float panorama_viewplane[4] = {0, 0, 0, 0};
  float panorama_frame_aspect = 0;
  float polynomial[5] = {-1.1735143712967577e-05f, -0.019988736953434998f, -3.3525322965709175e-06f,
                         3.099275275886036e-06f, -2.6064646454854524e-08f};
  // Motion blur: 0, or 2 to 129 transforms equally spaced over the shutter, the centre one xf
  // (Cycles interpolates them as objects', kernel/camera/camera.h); the lens stays as it is.
  std::vector<Transform> motion;
  // A perspective camera's zoom: the view plane's scale at the shutter's opening and closing
  // (lt_camera_desc.zoom_pre, zoom_post; 1: none).
  float zoom_pre = 1, zoom_post = 1;
};

// Cycles' aperture radius from Blender's F-stop (blender/camera.cpp): the focal length in metres
// (scene units, whatever the unit scale) over twice the F-stop, which is clamped to 1e-5; an
// orthographic camera has no focal length and takes 1 / (2 F-stop).
float aperture_radius_from_fstop(bool orthographic, float focal_length_mm, float fstop);

class Camera {
 public:
  Camera() = default;
  Camera(const CameraDesc& desc, int width, int height);
  // The ray through the film position (x, y) in pixels of the full frame, y up from the bottom,
  // from the lens point u_lens picks (ignored by a pinhole: has_lens()). False where the film
  // sees nothing (outside a fisheye's circle): Cycles leaves such samples black and opaque.
  // time: the shutter time of the sample (motion blur), which the ray carries.
  bool generate(float x, float y, Vec2 u_lens, Ray* ray, float time = 0.5f) const;
  // The pinhole's ray (no lens) through (x, y); false as generate.
  bool generate(float x, float y, Ray* ray) const { return generate(x, y, Vec2{0.5f, 0.5f}, ray); }
  // Whether the camera moves over the shutter.
  bool has_motion() const { return !motion_.empty() || zooms_; }
  // Cycles' compact ray differentials there (camera_sample_perspective / _orthographic /
  // _panorama, without depth of field): the footprint's size where the ray starts, at the near
  // clip (dP), and its growth per unit distance beyond it (dD: the angle between neighbouring
  // pixels' rays).
  void differentials(float x, float y, float* dP, float* dD) const;
  // Blender's Z depth of a world point: the distance along the viewing axis, or from the camera
  // for a panorama (Cycles' camera_z_depth), from the camera at the shutter's centre (as Cycles).
  float depth(const Vec3& p) const {
    return d_.panorama ? length(p - centre_.origin) : -dot(p - centre_.origin, centre_.forward_neg);
  }
  Vec3 position(float time = 0.5f) const { return basis(time).origin; }
  float clip_start() const { return d_.clip_start; }
  Vec3 forward(float time = 0.5f) const { return -basis(time).forward_neg; }
  bool orthographic() const { return d_.orthographic; }
  bool panorama() const { return d_.panorama; }
  // A thin lens with an aperture: camera rays start on it and draw a lens sample (one next_2d).
  bool has_lens() const { return d_.aperture_radius > 0; }
  // The point on the lens for the sample u (world space; the camera's position without a lens).
  // Uniform over the aperture's shape, whose area lens_area() is.
  Vec3 lens_point(Vec2 u, float time = 0.5f) const;
  float lens_area() const;
  int width() const { return width_; }  // the film: the full frame in pixels
  int height() const { return height_; }

  // Whether a point can be connected to the camera (BDPT's t = 1): a perspective or orthographic
  // camera, with or without a lens, and a panorama without one. Panoramas with depth of field (the
  // lens turns with the direction, so a lens point does not fix the ray) are not: their
  // connection strategy has density 0 and MIS leaves it out. Nor is a panorama whose map is
  // degenerate (an empty latitude or longitude range, a lens polynomial of k0 alone: one
  // direction for a whole area of film, a delta).
  bool connectable() const { return connectable_; }
  // BDPT's t = 1: the camera vertex a point p is connected to, for the lens sample u (drawn only
  // when has_lens()): the lens point of a perspective camera, the camera's position for a pinhole
  // or a panorama; for an orthographic camera, whose rays from one lens point are parallel (a sun
  // seen backwards), the point of its plane (with a lens, the near clip plane, where its rays
  // start) whose ray passes through p.
  Vec3 connection_point(const Vec3& p, Vec2 u, float time = 0.5f) const;

  // The film positions whose camera rays (from one lens point) have a given direction, with the
  // film's importance there: pixels of film per unit solid angle of direction (the inverse of
  // the direction map's Jacobian; pbrt-v4's camera importance We is it times the filter's value,
  // over cos^4 and the lens area for a perspective camera). A perspective camera has one such
  // position; a panorama can have several (a fisheye of more than 360 degrees, an equirectangular
  // film's seam and poles in the pixel filter's margin, a polynomial that is not monotonic), and
  // importance sums over them. An orthographic camera's rays from a lens point are parallel: its
  // importance is pixels per unit area across them (the measure a sun's emission has), with no
  // distance falloff (Projection::parallel).
  struct Preimage {
    Vec2 film;         // full-frame pixels, y up
    float importance;  // pixels per steradian (orthographic: per square metre across the rays)
  };
  static constexpr int kMaxPreimages = 48;  // radial: 4 monotonic pieces x 2 sides x 6 turns
  struct Projection {
    Vec3 dir;               // unit, from the lens point to the point
    float distance;         // from the lens point
    bool parallel = false;  // orthographic: importance per area across the rays
    // Where the camera ray from the lens point through the point starts along it (generate()'s
    // tmin, the near clip): nothing before it, medium or surface, is on that ray.
    float near = 0;
    int count = 0;
    Preimage at[kMaxPreimages];
  };
  // For connecting a point p to the camera vertex o (connection_point(); or a camera ray's
  // origin): the direction and distance from o to p, and every film position within `margin`
  // pixels of the frame (margin at most the frame's larger side) whose camera ray from o passes
  // through p. False if the camera is not connectable, or p is outside the rays' clipping range or
  // seen by no film position there (behind a perspective camera, outside a fisheye's circle).
  // An orthographic camera's film position is o's on its plane (o must be p's connection_point).
  bool project(const Vec3& o, const Vec3& p, float margin, Projection* out, float time = 0.5f) const;
  // The full-frame film position (pixels, y up) a world point projects to, seen by the camera at
  // shutter time `time` (the pinhole; no clipping, the film's bounds not checked), as Cycles'
  // worldtoraster for the Vector pass (a point behind the camera is mirrored, as its projection
  // divides by the depth). False for panoramas.
  bool raster(const Vec3& p, float time, Vec2* film) const;

 private:
  // The view plane (x, y at unit distance, or the orthographic plane) at film position (x, y).
  Vec2 plane_point(float x, float y) const {
    return {x0_ + (x1_ - x0_) * (x / width_), y0_ + (y1_ - y0_) * (y / height_)};
  }
  // The aperture offset (camera x, y in scene units) for the sample u.
  Vec2 aperture_offset(Vec2 u) const;
  // A panorama's direction in camera space (x right, y up, -z forward) at film position (x, y);
  // zero where the projection sees nothing.
  Vec3 panorama_direction(float x, float y) const;
  // The fisheyes as radial maps: the film point at radius rho (in the units of fisheye_scale(),
  // about the film's centre) sees the direction at angle theta(rho) from the axis, on its side
  // (its other side for a negative angle); visible where radial_visible.
  bool radial() const;
  double radial_theta(double rho) const;
  double radial_dtheta(double rho) const;
  bool radial_visible(double rho, double theta) const;
  Vec2 fisheye_scale() const;                 // film uv to radial units: (2, 2), or the fitted sensor in mm
  std::vector<double> radial_pieces() const;  // radial_ends_, at construction
  // Camera-space direction (unit) to the panorama's film positions (project()).
  void panorama_preimages(const Vec3& w, float margin, Projection* out) const;

  // The camera's position and axes (forward_neg: local +Z; the camera looks down -Z).
  struct Basis {
    Vec3 origin, right, up, forward_neg;
    Vec3 to_world(const Vec3& local) const { return right * local.x + up * local.y + forward_neg * local.z; }
  };
  static Basis basis_of(const Transform& xf);
  // At a shutter time: the centre's, or interpolated between the motion steps (moving_basis keeps
  // the last one per thread, for BDPT's many questions at one time; interpolated_basis does not,
  // for generate(), which asks once per sample).
  Basis basis(float time) const { return motion_.empty() ? centre_ : moving_basis(time); }
  Basis moving_basis(float time) const;
  Basis interpolated_basis(float time) const;
  // The view plane's scale at a shutter time (zooms_): from zoom_pre at 0 through 1 at the
  // centre to zoom_post at 1, linear on each half, as Cycles interpolates a raster position's point
  // between its perspective_pre, centre and perspective_post projections.
  float plane_scale(float time) const {
    if (!zooms_) return 1;
    return time < 0.5f ? d_.zoom_pre + (1 - d_.zoom_pre) * (2 * time) : 1 + (d_.zoom_post - 1) * (2 * time - 1);
  }
  // project() for an orthographic camera.
  bool project_orthographic(const Basis& b, const Vec3& o, float margin, Projection* out) const;
  // An orthographic camera with a lens: the near clip plane's centre, where its rays start.
  Vec3 ortho_lens_plane(const Basis& b) const { return b.origin - b.forward_neg * d_.clip_start; }

  CameraDesc d_;
  int width_ = 1, height_ = 1;
  float x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0;  // view plane at unit distance (or ortho plane)
  float pixel_area_ = 1;
  float fisheye_w_ = 36, fisheye_h_ = 24;  // the equisolid's and polynomial's sensor, fitted to the frame
  // A radial fisheye's rho range (the film within a frame's size of margin) cut where theta turns
  // (the lens polynomial's), so that theta is monotonic between consecutive ends: project()'s roots.
  std::vector<double> radial_ends_;
  bool connectable_ = true;
  bool zooms_ = false;  // a perspective camera whose view plane scales over the shutter
  Basis centre_;
  std::vector<DecomposedTransform> motion_;
  bool rigid_motion_ = false;  // every step without skew and with positive scales (interpolated_basis)
  uint64_t generation_ = 0;    // moving_basis()'s per-thread cache key (copies share the contents)
};

}  // namespace lt
