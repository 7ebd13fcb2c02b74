#include "robot/hand_check.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.h"
#include "robot/mjcf_compat.h"

namespace doasido::retarget {
namespace {

std::string Str(const char* s) { return s ? s : ""; }

std::string Range(double lo, double hi) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "[%.3g, %.3g]", lo, hi);
  return buf;
}

void CheckPoints(HandCheck& c) {
  const mjModel* m = c.model.get();
  const std::string hint = MissingBodyHint(c.xml);
  for (size_t i = 0; i < c.embodiment.points.size(); ++i) {
    const EmbodimentPoint& p = c.embodiment.points[i];
    if (PointBody(m, p) >= 0) continue;
    const std::string what = p.site.empty() ? "body '" + p.body + "'" : "site '" + p.site + "'";
    c.problems.push_back({kMissingBodyProblem,
                          "points[" + std::to_string(i) + "] (keypoint " + std::to_string(p.keypoint) +
                              ") names " + what + ", which " + c.embodiment.model_path.string() +
                              " does not have" + hint +
                              "; or name one of the bodies listed under chains"});
  }
}

void CheckJoints(HandCheck& c) {
  const mjModel* m = c.model.get();
  std::map<int, std::string> finger_of_joint;
  for (const HandChain& ch : c.structure.chains) {
    for (int j : ch.joints) finger_of_joint[j] = ch.finger;
  }
  std::map<int, int> actuator_of_joint;
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] == mjTRN_JOINT) actuator_of_joint[m->actuator_trnid[2 * a]] = a;
  }
  const std::string file = c.embodiment.model_path.string();
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) continue;
    JointReport r;
    r.name = Str(mj_id2name(m, mjOBJ_JOINT, j));
    r.finger = finger_of_joint.count(j) ? finger_of_joint[j] : "";
    r.limited = m->jnt_limited[j];
    r.lo = m->jnt_range[2 * j];
    r.hi = m->jnt_range[2 * j + 1];
    if (!r.limited) {
      c.problems.push_back({kUnlimitedJointProblem,
                            "joint '" + r.name + "' has no limits; the retargeter clamps to them and "
                            "the actuators take their range from them: give it range=\"lo hi\" and "
                            "limited=\"true\" in " + file});
    }
    if (actuator_of_joint.count(j)) {
      const int a = actuator_of_joint[j];
      r.actuator = Str(mj_id2name(m, mjOBJ_ACTUATOR, a));
      r.ctrl_limited = m->actuator_ctrllimited[a];
      r.ctrl_lo = m->actuator_ctrlrange[2 * a];
      r.ctrl_hi = m->actuator_ctrlrange[2 * a + 1];
      const bool position = m->actuator_biastype[a] == mjBIAS_AFFINE;
      const double tol = 1e-6;
      if (position && r.limited &&
          (!r.ctrl_limited || r.ctrl_lo < r.lo - tol || r.ctrl_hi > r.hi + tol)) {
        c.problems.push_back(
            {kActuatorRangeProblem,
             "position actuator '" + r.actuator + "' targets " +
                 (r.ctrl_limited ? Range(r.ctrl_lo, r.ctrl_hi) : std::string("any position")) +
                 " beyond joint '" + r.name + "' range " + Range(r.lo, r.hi) +
                 ": set ctrllimited=\"true\" ctrlrange within the joint range in " + file});
      }
    }
    c.joints.push_back(r);
  }
}

// Fingertip points should lie on a chain's distal body (or a body below
// its last hinge); the thumb tip on the opposing chain.
void CheckTips(HandCheck& c) {
  const mjModel* m = c.model.get();
  if (c.structure.chains.empty()) return;
  auto chain_of_tip = [&](int body) -> const HandChain* {
    for (const HandChain& ch : c.structure.chains) {
      const int last_hinge_body = m->jnt_bodyid[ch.joints.back()];
      auto it = std::find(ch.bodies.begin(), ch.bodies.end(), last_hinge_body);
      if (std::find(it, ch.bodies.end(), body) != ch.bodies.end()) return &ch;
    }
    return nullptr;
  };
  for (size_t i = 0; i < c.embodiment.points.size(); ++i) {
    const EmbodimentPoint& p = c.embodiment.points[i];
    const int body = PointBody(m, p);
    if (!p.fingertip || body < 0) continue;
    const HandChain* ch = chain_of_tip(body);
    const std::string where = "points[" + std::to_string(i) + "] (keypoint " + std::to_string(p.keypoint) + ")";
    const std::string name = Str(mj_id2name(m, mjOBJ_BODY, body));
    if (!ch) {
      c.problems.push_back({kTipNotDistalProblem,
                            where + " is a fingertip on body '" + name + "', which is not the distal "
                            "part of any finger chain (see chains); move it to a chain's tip body"});
    } else if (p.keypoint == 4 && ch != &c.structure.chains.front()) {
      c.problems.push_back({kThumbMismatchProblem,
                            where + " (thumb tip) is on the " + ch->finger + " chain, but the chain "
                            "that opposes the others ends at '" +
                                Str(mj_id2name(m, mjOBJ_BODY, c.structure.chains.front().tip_body)) +
                                "'; check which finger is the thumb"});
    }
  }
}

}  // namespace

HandCheck CheckHand(const std::filesystem::path& description, const std::filesystem::path& robots_dir) {
  return CheckHand(LoadEmbodiment(description, robots_dir));
}

HandCheck CheckHand(const Embodiment& embodiment) {
  HandCheck c;
  c.embodiment = embodiment;
  c.xml = PrepareMjcf(c.embodiment.model_path).xml;
  c.model = CompileMjcfText(c.xml, c.embodiment.model_path.string());
  CheckPoints(c);
  try {
    c.structure = AnalyzeHand(c.model.get(), c.embodiment.model_path.string());
  } catch (const Error& e) {
    c.problems.push_back({kNoChainsProblem, e.message()});
  }
  CheckJoints(c);
  CheckTips(c);
  return c;
}

Eigen::VectorXd FlexedPose(const mjModel* m, const HandStructure& s, double fraction) {
  Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(m->qpos0, m->nq);
  std::vector<bool> flex(m->njnt, false);
  for (const HandChain& ch : s.chains) {
    for (int j : ch.flexion) flex[j] = true;
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) continue;
    const double lo = m->jnt_limited[j] ? m->jnt_range[2 * j] : -M_PI;
    const double hi = m->jnt_limited[j] ? m->jnt_range[2 * j + 1] : M_PI;
    const double rest = std::clamp(0.0, lo, hi);
    const double end = std::abs(hi) >= std::abs(lo) ? hi : lo;
    q[m->jnt_qposadr[j]] = flex[j] ? rest + fraction * (end - rest) : rest;
  }
  return q;
}

}  // namespace doasido::retarget
