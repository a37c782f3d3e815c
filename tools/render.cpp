#include "tools/render.hpp"

#include "nodes/mesh_leaf.hpp"

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <stb/stb_image_write.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace ht::render {
namespace {

using glm::dvec3;

constexpr double kFov = 30.0 * std::numbers::pi / 180.0;  // vertical
constexpr int kSamples = 2;                               // a side: 2 x 2 rays a pixel
const dvec3 kBackground(0.97, 0.97, 0.96), kSolid(0.86, 0.60, 0.42), kLeaf(0.88, 0.89, 0.92), kEdge(0.12, 0.13, 0.16);

struct Camera {
  dvec3 eye, forward, right, up;
  double tan_y = 0, tan_x = 0;
  int width = 0, height = 0;

  // The direction of the ray through image point (x, y), in pixels from the top left corner.
  dvec3 ray(double x, double y) const {
    const double sx = (2.0 * x / width - 1.0) * tan_x, sy = (1.0 - 2.0 * y / height) * tan_y;
    return glm::normalize(forward + sx * right + sy * up);
  }
  // Where q lands in the image, in pixels (q in front of the eye).
  glm::dvec2 project(const dvec3& q) const {
    const dvec3 v = q - eye;
    const double z = std::max(glm::dot(v, forward), 1e-300);
    return {(glm::dot(v, right) / z / tan_x + 1.0) * 0.5 * width, (1.0 - glm::dot(v, up) / z / tan_y) * 0.5 * height};
  }
};

Camera look_at(const TriangleMesh& mesh, const Options& o) {
  dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const dvec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const dvec3 centre = 0.5 * (lo + hi);
  double radius = 1e-9;  // of the sphere around the box's centre that holds every vertex
  for (const dvec3& p : mesh.positions) radius = std::max(radius, glm::length(p - centre));
  const double az = o.azimuth * std::numbers::pi / 180.0, el = o.elevation * std::numbers::pi / 180.0;
  const dvec3 towards_eye(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  Camera c;
  c.width = o.width;
  c.height = o.height;
  c.tan_y = std::tan(0.5 * kFov);
  c.tan_x = c.tan_y * double(o.width) / double(o.height);
  // The bounding sphere fits the narrower of the two fields of view, with a small margin.
  const double half = std::atan(std::min(c.tan_x, c.tan_y));
  c.eye = centre + towards_eye * (1.03 * radius / std::sin(half));
  c.forward = -towards_eye;
  const dvec3 world_up = std::abs(towards_eye.y) > 0.999 ? dvec3(0, 0, -1) : dvec3(0, 1, 0);
  c.right = glm::normalize(glm::cross(c.forward, world_up));
  c.up = glm::cross(c.right, c.forward);
  return c;
}

// The Embree scene of the mesh's triangles (float), owned for the drawing's duration.
struct Scene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  explicit Scene(const TriangleMesh& mesh) {
    device = rtcNewDevice("threads=1");  // built once; the pixels run in parallel on TBB
    if (!device) throw RenderError("render: Embree could not start");
    scene = rtcNewScene(device);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.positions.size()));
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), mesh.triangles.size()));
    if (!v || !t) throw RenderError("render: Embree could not hold the mesh");
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
      for (int k = 0; k < 3; ++k) v[3 * i + std::size_t(k)] = static_cast<float>(mesh.positions[i][k]);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (int k = 0; k < 3; ++k) t[3 * i + std::size_t(k)] = mesh.triangles[i][k];
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
  }
  ~Scene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
};

double distance_to_segment(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

// The colour one ray sees.
dvec3 shade(const TriangleMesh& mesh, std::span<const std::uint8_t> outlined, const Camera& cam, RTCScene scene,
            double x, double y) {
  const dvec3 d = cam.ray(x, y);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = float(cam.eye.x), rh.ray.org_y = float(cam.eye.y), rh.ray.org_z = float(cam.eye.z);
  rh.ray.dir_x = float(d.x), rh.ray.dir_y = float(d.y), rh.ray.dir_z = float(d.z);
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = ~0u;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return kBackground;
  const std::size_t tri = rh.hit.primID;
  dvec3 n = glm::normalize(dvec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
  if (glm::dot(n, d) > 0) n = -n;  // a back face (an open patch) lit like a front one
  // A key light above and to the left of the eye, and a soft fill from the eye.
  const dvec3 key = glm::normalize(-cam.forward + 0.7 * cam.up - 0.5 * cam.right);
  const double light = 0.22 + 0.58 * std::max(0.0, glm::dot(n, key)) + 0.2 * std::max(0.0, -glm::dot(n, d));
  const bool leaf = !outlined.empty() && outlined[tri];
  const dvec3 base = (leaf ? kLeaf : kSolid) * light;
  if (!leaf) return base;
  const auto& t = mesh.triangles[tri];
  const glm::dvec2 p(x, y), a = cam.project(mesh.positions[t[0]]), b = cam.project(mesh.positions[t[1]]),
                   c = cam.project(mesh.positions[t[2]]);
  const double edge = std::min({distance_to_segment(p, a, b), distance_to_segment(p, b, c), distance_to_segment(p, c, a)});
  const double ink = std::clamp(1.0 - edge / 0.6, 0.0, 1.0);  // lines about a pixel wide
  return base * (1.0 - ink) + kEdge * ink;
}

std::uint8_t to_byte(double linear) {
  return static_cast<std::uint8_t>(std::lround(255.0 * std::pow(std::clamp(linear, 0.0, 1.0), 1.0 / 2.2)));
}

}  // namespace

Image draw(const TriangleMesh& mesh, std::span<const std::uint8_t> outlined, const Options& o) {
  if (!(o.width >= 16 && o.width <= 8192 && o.height >= 16 && o.height <= 8192))
    throw RenderError("render: the size must be 16 to 8192 pixels a side, not " + std::to_string(o.width) + " x " +
                      std::to_string(o.height));
  if (!std::isfinite(o.azimuth) || !std::isfinite(o.elevation)) throw RenderError("render: the view angles must be finite");
  if (!outlined.empty() && outlined.size() != mesh.triangles.size())
    throw RenderError("render: one outline flag a triangle is needed");
  for (const dvec3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw RenderError("render: the mesh has a vertex that is not finite");
  Image img;
  img.width = o.width;
  img.height = o.height;
  img.rgb.assign(std::size_t(o.width) * std::size_t(o.height) * 3, 0);
  if (mesh.triangles.empty()) {
    std::fill(img.rgb.begin(), img.rgb.end(), to_byte(kBackground.x));
    return img;
  }
  const Camera cam = look_at(mesh, o);
  const Scene scene(mesh);
  tbb::parallel_for(0, o.height, [&](int row) {
    for (int col = 0; col < o.width; ++col) {
      dvec3 sum(0.0);
      for (int sy = 0; sy < kSamples; ++sy)
        for (int sx = 0; sx < kSamples; ++sx)
          sum += shade(mesh, outlined, cam, scene.scene, col + (sx + 0.5) / kSamples, row + (sy + 0.5) / kSamples);
      const dvec3 c = sum / double(kSamples * kSamples);
      std::uint8_t* px = img.rgb.data() + (std::size_t(row) * std::size_t(o.width) + std::size_t(col)) * 3;
      px[0] = to_byte(c.x), px[1] = to_byte(c.y), px[2] = to_byte(c.z);
    }
  });
  return img;
}

std::vector<std::uint8_t> on_mesh_leaves(const TriangleMesh& mesh, const Graph& graph, double tolerance) {
  std::vector<std::uint8_t> on_vertex(mesh.positions.size(), 0), out(mesh.triangles.size(), 0);
  if (graph.meshes.empty()) return out;
  tbb::parallel_for(std::size_t(0), mesh.positions.size(), [&](std::size_t v) {
    for (const auto& leaf : graph.meshes)
      if (leaf && std::isfinite(leaf->query(mesh.positions[v], tolerance).distance)) {
        on_vertex[v] = 1;
        break;
      }
  });
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    out[t] = on_vertex[tri[0]] & on_vertex[tri[1]] & on_vertex[tri[2]];
  }
  return out;
}

std::string encode_png(const Image& image) {
  std::string bytes;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), std::size_t(size));
  };
  if (!stbi_write_png_to_func(append, &bytes, image.width, image.height, 3, image.rgb.data(), image.width * 3))
    throw RenderError("render: the PNG could not be encoded");
  return bytes;
}

}  // namespace ht::render
