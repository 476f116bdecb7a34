#include "keepless/core/config.hpp"

#include <cstddef>
#include <cstring>
#include <initializer_list>

namespace keepless::core {

const char* to_string(Scope scope) {
  switch (scope) {
    case Scope::kNewest: return "newest";
    case Scope::kAuto: return "auto";
    case Scope::kWindow: break;
  }
  return "window";
}

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
  for (Scope s : {Scope::kWindow, Scope::kNewest, Scope::kAuto}) {
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

namespace {

struct NamedBit {
  const char* name;
  std::uint8_t bit;
};

// A comma-separated list of `names`, each at most once, as their bits.
template <std::size_t N>
bool parse_bits(const char* text, const NamedBit (&names)[N], std::uint8_t* out) {
  std::uint8_t bits = 0;
  const char* at = text;
  for (;;) {
    const char* end = std::strchr(at, ',');
    const std::size_t n = end != nullptr ? static_cast<std::size_t>(end - at) : std::strlen(at);
    std::uint8_t bit = 0;
    for (const NamedBit& t : names) {
      if (std::strlen(t.name) == n && std::strncmp(at, t.name, n) == 0) bit = t.bit;
    }
    if (bit == 0 || (bits & bit) != 0) return false;
    bits = static_cast<std::uint8_t>(bits | bit);
    if (end == nullptr) break;
    at = end + 1;
  }
  *out = bits;
  return true;
}

}  // namespace

bool parse_track_terms(const char* text, std::uint8_t* out) {
  static constexpr NamedBit kTerms[] = {
      {"length", kTrackLength}, {"age", kTrackAge}, {"error", kTrackError}, {"angle", kTrackAngle}};
  return parse_bits(text, kTerms, out);
}

bool parse_cost_terms(const char* text, std::uint8_t* out) {
  static constexpr NamedBit kTerms[] = {
      {"c_c", kConnectivityCost}, {"c_s", kSpatialCost}, {"c_b", kBaselineCost}};
  return parse_bits(text, kTerms, out);
}

}  // namespace keepless::core
