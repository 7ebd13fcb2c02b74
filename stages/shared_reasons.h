// Reason codes that more than one stage gives, one constant each now that
// every stage is in namespace doasido::stages: no hands (the hands stage
// found none; recon: a hand-only bundle with no valid frame) and no object
// (recon, dynamic retargeting).
#pragma once

namespace doasido::stages {

inline constexpr const char* kReasonNoHands = "no_hands";
inline constexpr const char* kReasonNoObject = "no_object";

}  // namespace doasido::stages
