// The issue-11 BlueROV2 coupling scene and its runner, shared by tests/coupling_test.cc and
// tests/coupling_consistent_test.cc (docs/coupling.md).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"

namespace mjtether {
namespace {

inline bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

inline std::string Replace(std::string s, const std::string& from, const std::string& to) {
  const size_t i = s.find(from);
  EXPECT_NE(i, std::string::npos) << from;
  if (i != std::string::npos) s.replace(i, from.size(), to);
  return s;
}

// The scene from the shipped model: EA and EAc, the integrator and the MuJoCo step
// replaced, the vehicle 29.5 m from the reel (site at x = 29.5 m), four thrusters at 40 N.
inline std::string BlueRovXml(const std::string& EA, const std::string& integrator, double timestep) {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/bluerov2_heavy.xml");
  std::stringstream s;
  s << f.rdbuf();
  std::string xml = s.str();
  xml = Replace(xml, "EA=6e4 EAc=6e4", "EA=" + EA + " EAc=" + EA);
  xml = Replace(xml, "Can=1.0\"/>", "Can=1.0 integrator=" + integrator + "\"/>");
  xml = Replace(xml, "<body name=\"rov\" pos=\"8 0 -10\">",
                "<body name=\"rov\" pos=\"29.729 0 -0.3\">");
  xml = Replace(xml, "timestep=\"0.002\"", "timestep=\"" + std::to_string(timestep) + "\"");
  const size_t i = xml.rfind("<text name=\"motion:boat\"");
  xml.insert(i,
             "<text name=\"thrust:fr\" data=\"t=0 ctrl=40\"/><text name=\"thrust:fl\" "
             "data=\"t=0 ctrl=40\"/><text name=\"thrust:rr\" data=\"t=0 ctrl=40\"/><text "
             "name=\"thrust:rl\" data=\"t=0 ctrl=40\"/>\n");
  return xml;
}

struct Sample {
  double t;
  Eigen::Vector3d pos;  // [m] vehicle origin
  double tension;       // [N] at the vehicle's end
};

// Runs the scene for `duration` s, sampling every `interval` s (0.05 s unless given; at least
// every step); stops at a divergence or chatter report, returned in *stopped.
inline std::vector<Sample> RunScene(mjModel* m, double duration, std::string* stopped,
                                    double interval = 0.05) {
  mjData* d = mj_makeData(m);
  const int rov = mj_name2id(m, mjOBJ_BODY, "rov");
  const long long steps = std::llround(duration / m->opt.timestep);
  const long long every = std::max(1LL, std::llround(interval / m->opt.timestep));
  std::vector<Sample> out;
  for (long long i = 0; i <= steps; ++i) {
    Prescribe(m, d);
    if (i % every == 0) {
      mj_forward(m, d);
      out.push_back({d->time, Eigen::Vector3d(d->xpos + 3 * rov), GetReactions(m, d, 0).tension_b});
    }
    if (i == steps) break;
    mj_step(m, d);
    if (std::optional<std::string> s = CheckDivergence(m, d)) {
      *stopped = *s;
      break;
    }
  }
  mj_deleteData(d);
  return out;
}

}  // namespace
}  // namespace mjtether
