#include "keepless/core/config.hpp"

#include <cstring>
#include <initializer_list>

namespace keepless::core {

const char* to_string(Scope scope) { return scope == Scope::kNewest ? "newest" : "window"; }

const char* to_string(CostModel model) {
  switch (model) {
    case CostModel::kAuthors: return "authors";
    case CostModel::kInformation: return "information";
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
  for (CostModel m : {CostModel::kPaper, CostModel::kAuthors, CostModel::kInformation}) {
    if (std::strcmp(text, to_string(m)) == 0) {
      *out = m;
      return true;
    }
  }
  return false;
}

}  // namespace keepless::core
