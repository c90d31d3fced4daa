#include "lab/scenario/lab_randomize.h"

#include <algorithm>
#include <cmath>

#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"
#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

constexpr int kAttemptsPerBody = 2000;  // as `vlab cubes` (vision_scene.cc)

// uniform in [0, 1) from the top 53 bits: the same numbers on every platform (as vision_scene.cc)
double Uniform(sensors::Xoshiro256pp& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// x: [min, max], y: [min, max] of a rectangle mapping
RandomizeRect ReadRect(MapReader r) {
  RandomizeRect rect;
  const std::vector<double> x = r.Numbers("x", {});
  const std::vector<double> y = r.Numbers("y", {});
  if (x.size() != 2 || !(x[0] < x[1])) r.Fail("x", "expected [min, max] with min < max, m (world)");
  if (y.size() != 2 || !(y[0] < y[1])) r.Fail("y", "expected [min, max] with min < max, m (world)");
  r.Finish();
  rect.x_min = x[0];
  rect.x_max = x[1];
  rect.y_min = y[0];
  rect.y_max = y[1];
  return rect;
}

// distance from a point to a rectangle (0 inside)
double DistanceTo(const RandomizeRect& r, const Eigen::Vector2d& p) {
  const double dx = std::max({r.x_min - p.x(), 0.0, p.x() - r.x_max});
  const double dy = std::max({r.y_min - p.y(), 0.0, p.y() - r.y_max});
  return std::hypot(dx, dy);
}

// the body's collision geometry as a box in its own frame: box geoms exactly, others by their
// bounding sphere; lo, hi per axis
struct Extent {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
};

Extent BodyExtent(const mjModel* m, int body) {
  Extent e;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] != body || (m->geom_contype[g] == 0 && m->geom_conaffinity[g] == 0)) continue;
    const Eigen::Vector3d pos(m->geom_pos + 3 * g);
    Eigen::Vector3d half = Eigen::Vector3d::Constant(m->geom_rbound[g]);
    if (m->geom_type[g] == mjGEOM_BOX) {
      const double* q = m->geom_quat + 4 * g;
      const Eigen::Matrix3d R = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
      half = R.cwiseAbs() * Eigen::Vector3d(m->geom_size + 3 * g);
    }
    e.lo = e.lo.cwiseMin(pos - half);
    e.hi = e.hi.cwiseMax(pos + half);
  }
  return e;
}

// radius of the footprint (about the body origin) when face `face` is down, and the origin's
// height above the surface
double FootprintRadius(const Extent& e, int face) {
  const int axis = face / 2;
  double r2 = 0;
  for (int k = 0; k < 3; ++k) {
    if (k != axis) r2 += std::pow(std::max(std::abs(e.lo[k]), std::abs(e.hi[k])), 2);
  }
  return std::sqrt(r2);
}
double RestingHeight(const Extent& e, int face) { return face % 2 == 0 ? e.hi[face / 2] : -e.lo[face / 2]; }

}  // namespace

Eigen::Quaterniond RestingOn(int face) {
  const double half_pi = M_PI / 2;
  switch (face) {
    case 0:
      return Eigen::Quaterniond(Eigen::AngleAxisd(half_pi, Eigen::Vector3d::UnitY()));
    case 1:
      return Eigen::Quaterniond(Eigen::AngleAxisd(-half_pi, Eigen::Vector3d::UnitY()));
    case 2:
      return Eigen::Quaterniond(Eigen::AngleAxisd(-half_pi, Eigen::Vector3d::UnitX()));
    case 3:
      return Eigen::Quaterniond(Eigen::AngleAxisd(half_pi, Eigen::Vector3d::UnitX()));
    case 4:
      return Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
    default:
      return Eigen::Quaterniond::Identity();
  }
}

RandomizeConfig ReadRandomize(MapReader& r) {
  RandomizeConfig c;
  c.where = YamlWhere(r.file(), r.node());
  c.bodies = r.Strings("bodies", {});
  if (c.bodies.empty()) r.Fail("bodies", "expected a list of bodies with a free joint, e.g. [cube_A, cube_B]");
  for (std::size_t i = 0; i < c.bodies.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (c.bodies[i] == c.bodies[j]) r.Fail("bodies", "body '" + c.bodies[i] + "' named twice");
    }
  }
  if (!r.Has("region")) r.Fail("region", "required: {x: [min, max], y: [min, max]} (m, world)");
  c.region = ReadRect(r.Map("region"));
  if (r.Has("within")) {
    MapReader w = r.Map("within");
    const std::vector<double> center = w.Numbers("center", {});
    if (center.size() != 2) w.Fail("center", "expected [x, y], m (world)");
    c.within_center = Eigen::Vector2d(center[0], center[1]);
    c.within_radius = w.Number("radius");
    if (!(c.within_radius > 0)) w.Fail("radius", "must be > 0 m");
    w.Finish();
    c.has_within = true;
  }
  const YAML::Node exclude = r.Sequence("exclude");
  for (std::size_t i = 0; i < exclude.size(); ++i) {
    c.exclude.push_back(ReadRect(MapReader(r.file(), exclude[i], r.Child("exclude") + "[" + std::to_string(i) + "]")));
  }
  c.clearance_m = r.Number("clearance", c.clearance_m);
  if (!(c.clearance_m >= 0 && c.clearance_m < 1)) r.Fail("clearance", "must be >= 0 and < 1 m");
  c.surface_z = r.Number("surface");
  c.drop_m = r.Number("drop", c.drop_m);
  if (!(c.drop_m >= 0 && c.drop_m <= 0.1)) r.Fail("drop", "must be 0 to 0.1 m");
  const YAML::Node face = r.Raw("resting_face");
  if (face && !(face.IsScalar() && face.as<std::string>() == "any")) {
    double f = -1;
    try {
      f = YamlNumber(r.file(), face, r.Child("resting_face"));
    } catch (const InputError&) {
      f = -1;  // not a number: the message below
    }
    if (f != std::floor(f) || f < 0 || f > 5) r.Fail("resting_face", "expected any, or a face 0-5 (+X -X +Y -Y +Z -Z)");
    c.resting_face = static_cast<int>(f);
  }
  const YAML::Node yaw = r.Raw("yaw");
  if (yaw && !(yaw.IsScalar() && yaw.as<std::string>() == "any")) {
    if (!yaw.IsSequence()) r.Fail("yaw", "expected any, or [min, max] (deg)");
    const std::vector<double> range = YamlNumbers(r.file(), yaw, r.Child("yaw"));
    if (range.size() != 2 || !(range[0] <= range[1]) || range[1] - range[0] > 360) {
      r.Fail("yaw", "expected any, or [min, max] with min <= max, at most 360 deg apart");
    }
    c.yaw_min_deg = range[0];
    c.yaw_max_deg = range[1];
  }
  r.Finish();
  return c;
}

std::unique_ptr<Randomizer> Randomizer::Create(const mjModel* m, const RandomizeConfig& c, std::uint64_t seed) {
  auto out = std::unique_ptr<Randomizer>(new Randomizer());
  const std::string prefix = c.where + ": randomize: ";
  // bind: each body has exactly one joint, a free one
  std::vector<Extent> extents;
  for (const std::string& name : c.bodies) {
    const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
    if (b < 0) throw InputError(prefix + "bodies: the scene has no body '" + name + "'");
    if (m->body_jntnum[b] != 1 || m->jnt_type[m->body_jntadr[b]] != mjJNT_FREE) {
      throw InputError(prefix + "bodies: body '" + name + "' must have one joint, a free joint");
    }
    const Extent e = BodyExtent(m, b);
    if (!(e.lo.x() <= e.hi.x())) throw InputError(prefix + "bodies: body '" + name + "' has no collision geom");
    extents.push_back(e);
    out->qpos_adr_.push_back(m->jnt_qposadr[m->body_jntadr[b]]);
    out->dof_adr_.push_back(m->jnt_dofadr[m->body_jntadr[b]]);
  }

  sensors::Xoshiro256pp rng(seed);
  std::vector<double> radii;
  for (std::size_t i = 0; i < c.bodies.size(); ++i) {
    // the footprint's radius: the largest over the faces it may rest on (drawn after the centre)
    double radius = 0;
    for (int f = 0; f < 6; ++f) {
      if (c.resting_face < 0 || c.resting_face == f) radius = std::max(radius, FootprintRadius(extents[i], f));
    }
    const RandomizeRect& a = c.region;
    const double x_lo = a.x_min + radius, x_hi = a.x_max - radius;
    const double y_lo = a.y_min + radius, y_hi = a.y_max - radius;
    if (!(x_lo < x_hi && y_lo < y_hi)) {
      throw InputError(prefix + "region: smaller than body '" + c.bodies[i] + "' (footprint radius " +
                       FormatDouble(radius) + " m)");
    }
    RandomPlacement p;
    p.body = mj_name2id(m, mjOBJ_BODY, c.bodies[i].c_str());
    bool found = false;
    Eigen::Vector2d xy;
    for (int attempt = 0; attempt < kAttemptsPerBody && !found; ++attempt) {
      xy = Eigen::Vector2d(x_lo + (x_hi - x_lo) * Uniform(rng), y_lo + (y_hi - y_lo) * Uniform(rng));
      found = !c.has_within || (xy - c.within_center).norm() <= c.within_radius;
      for (const RandomizeRect& r : c.exclude) found = found && DistanceTo(r, xy) >= radius + c.clearance_m;
      for (std::size_t j = 0; j < out->placements_.size(); ++j) {
        found = found && (xy - out->placements_[j].position.head<2>()).norm() >= radius + radii[j] + c.clearance_m;
      }
    }
    if (!found) {
      throw InputError(prefix + "body '" + c.bodies[i] + "' does not fit: " + std::to_string(i) +
                       " bodies placed, no free spot in " + std::to_string(kAttemptsPerBody) + " draws (seed " +
                       std::to_string(seed) + "); widen the region or lower the clearance");
    }
    const int face = static_cast<int>(Uniform(rng) * 6);
    p.face_down = c.resting_face < 0 ? face : c.resting_face;
    p.yaw_deg = c.yaw_min_deg + (c.yaw_max_deg - c.yaw_min_deg) * Uniform(rng);
    p.position = Eigen::Vector3d(xy.x(), xy.y(), c.surface_z + RestingHeight(extents[i], p.face_down) + c.drop_m);
    p.orientation = Eigen::AngleAxisd(p.yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()) * RestingOn(p.face_down);
    if (p.orientation.w() < 0) p.orientation.coeffs() *= -1;  // the same rotation, written with w >= 0
    out->placements_.push_back(p);
    radii.push_back(radius);
  }
  return out;
}

void Randomizer::Apply(const mjModel* m, mjData* d) const {
  (void)m;
  for (std::size_t i = 0; i < placements_.size(); ++i) {
    const RandomPlacement& p = placements_[i];
    double* q = d->qpos + qpos_adr_[i];
    q[0] = p.position.x();
    q[1] = p.position.y();
    q[2] = p.position.z();
    q[3] = p.orientation.w();
    q[4] = p.orientation.x();
    q[5] = p.orientation.y();
    q[6] = p.orientation.z();
    for (int k = 0; k < 6; ++k) d->qvel[dof_adr_[i] + k] = 0;
  }
}

}  // namespace vlab::lab
