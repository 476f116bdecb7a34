#include "keepless/core/config.hpp"

#include <cstring>
#include <initializer_list>

namespace keepless::core {

const char* to_string(Scope scope) { return scope == Scope::kNewest ? "newest" : "window"; }

const char* to_string(CostModel model) {
  switch (model) {
    case CostModel::kAuthors: return "authors";
    case CostModel::kInformation: return "information";
    case CostModel::kTrack: return "track";
    case CostModel::kPaper: break;
  }
  return "paper";
}

const char* to_string(BudgetKind kind) {
  switch (kind) {
    case BudgetKind::kPoints: return "points";
    case BudgetKind::kFraction: return "fraction";
    case BudgetKind::kObservations: return "observations";
    case BudgetKind::kNone: break;
  }
  return "none";
}

bool parse_scope(const char* text, Scope* out) {
  for (Scope s : {Scope::kWindow, Scope::kNewest}) {
    if (std::strcmp(text, to_string(s)) == 0) {
      *out = s;
      return true;
    }
  }
  return false;
}

bool parse_cost_model(const char* text, CostModel* out) {
  for (CostModel m : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation,
                      CostModel::kTrack}) {
    if (std::strcmp(text, to_string(m)) == 0) {
      *out = m;
      return true;
    }
  }
  return false;
}

bool parse_track_terms(const char* text, std::uint8_t* out) {
  static constexpr struct {
    const char* name;
    std::uint8_t bit;
  } kTerms[] = {{"length", kTrackLength}, {"age", kTrackAge}, {"error", kTrackError}, {"angle", kTrackAngle}};
  std::uint8_t terms = 0;
  const char* at = text;
  for (;;) {
    const char* end = std::strchr(at, ',');
    const std::size_t n = end != nullptr ? static_cast<std::size_t>(end - at) : std::strlen(at);
    std::uint8_t bit = 0;
    for (const auto& t : kTerms) {
      if (std::strlen(t.name) == n && std::strncmp(at, t.name, n) == 0) bit = t.bit;
    }
    if (bit == 0 || (terms & bit) != 0) return false;
    terms = static_cast<std::uint8_t>(terms | bit);
    if (end == nullptr) break;
    at = end + 1;
  }
  *out = terms;
  return true;
}

}  // namespace keepless::core
