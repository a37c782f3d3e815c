#include "tools/scenes.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace ht::scenes {
namespace {

struct CurveSpec {
  std::vector<glm::dvec3> points;
  double radius;
};

// The body: pieces of a sinuous spine, each a 4-point curve overlapping its neighbours so the
// blend is smooth; radius tapers toward the tail. The rest of the primitives are fins: short
// curves standing on the back.
std::vector<CurveSpec> snake_specs(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  const int body = std::max(1, (count * 4) / 5);
  const int fins = count - body;
  const double length = 12.0;
  auto spine = [&](double s) {
    const double t = s / length;
    return glm::dvec3(s, 1.2 * std::sin(2.0 * std::numbers::pi * 1.5 * t) * (0.3 + t),
                      0.5 * std::sin(2.0 * std::numbers::pi * 0.75 * t) + 0.8 * (1.0 - t) * (1.0 - t));
  };
  auto thickness = [&](double s) { return 0.22 + 0.38 * (1.0 - s / length) + 0.1 * std::exp(-s * s); };
  std::vector<CurveSpec> out;
  const double step = length / body;
  for (int i = 0; i < body; ++i) {
    const double s0 = i * step;
    CurveSpec c;
    for (int k = 0; k < 4; ++k) c.points.push_back(spine(s0 + (k - 0.5) * step * 0.9));
    c.radius = thickness(s0) * (1.0 + 0.05 * jitter(rng)) + 0.35;
    out.push_back(c);
  }
  for (int i = 0; i < fins; ++i) {
    const double s = length * (0.1 + 0.8 * (i + 0.5) / fins);
    const glm::dvec3 base = spine(s);
    const double h = 0.35 + 0.15 * jitter(rng);
    CurveSpec c;
    c.points = {base, base + glm::dvec3(0.1, 0.0, 0.6 * h), base + glm::dvec3(0.25, 0.05 * jitter(rng), h)};
    c.radius = 0.3;
    out.push_back(c);
  }
  return out;
}

}  // namespace

NodeId snake(Builder& b, int count, std::uint64_t seed) {
  std::vector<NodeId> parts;
  for (const CurveSpec& c : snake_specs(count, seed)) parts.push_back(b.curve(c.points, {c.radius, 1.0}));
  return b.blend(parts);
}

std::string snake_json(int count, std::uint64_t seed) {
  std::string out = "{\n  \"hybridtree\": 1,\n  \"threshold\": 0.5,\n  \"root\": {\"type\": \"blend\", \"name\": \"snake\", \"children\": [\n";
  const auto specs = snake_specs(count, seed);
  char buf[256];
  for (std::size_t i = 0; i < specs.size(); ++i) {
    out += "    {\"type\": \"curve\", \"radius\": ";
    std::snprintf(buf, sizeof buf, "%.17g", specs[i].radius);
    out += buf;
    out += ", \"points\": [";
    for (std::size_t k = 0; k < specs[i].points.size(); ++k) {
      const auto& p = specs[i].points[k];
      std::snprintf(buf, sizeof buf, "%s[%.17g, %.17g, %.17g]", k ? ", " : "", p.x, p.y, p.z);
      out += buf;
    }
    out += i + 1 < specs.size() ? "]},\n" : "]}\n";
  }
  out += "  ]}\n}\n";
  return out;
}

}  // namespace ht::scenes
