#include "keepless/core/use.hpp"

#include <cstring>
#include <initializer_list>

namespace keepless::core {

void apply_use(Use use, Params* params) {
  const Params paper{};
  params->scope = paper.scope;
  params->maturity_keyframes = paper.maturity_keyframes;
  params->defer_keyframes = paper.defer_keyframes;
  params->budget.track_share = paper.budget.track_share;
  params->budget.track_share_from = paper.budget.track_share_from;
  params->budget.track_share_to = paper.budget.track_share_to;
  switch (use) {
    case Use::kMonocular:
      params->budget.track_share = 0.5;
      params->budget.track_share_from = 0.3;
      [[fallthrough]];
    case Use::kRgbd:
      params->scope = Scope::kNewest;
      params->maturity_keyframes = 2;
      break;
    case Use::kMonocularDeferred:
      params->defer_keyframes = 2;
      params->scope = Scope::kAuto;
      params->budget.track_share = 0.5;
      params->budget.track_share_to = 0.15;
      break;
    case Use::kOffline: params->budget.track_share = 1.0; break;
    case Use::kPaper: break;
  }
}

const char* to_string(Use use) {
  switch (use) {
    case Use::kMonocular: return "monocular";
    case Use::kMonocularDeferred: return "monocular-deferred";
    case Use::kRgbd: return "rgbd";
    case Use::kOffline: return "offline";
    case Use::kPaper: break;
  }
  return "paper";
}

bool parse_use(const char* text, Use* out) {
  for (Use u : {Use::kPaper, Use::kMonocular, Use::kMonocularDeferred, Use::kRgbd, Use::kOffline}) {
    if (std::strcmp(text, to_string(u)) == 0) {
      *out = u;
      return true;
    }
  }
  return false;
}

}  // namespace keepless::core
