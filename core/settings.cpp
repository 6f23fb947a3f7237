#include "core/settings.hpp"

namespace palpable {

std::string_view to_string(RestitutionLaw law) {
  switch (law) {
    case RestitutionLaw::kStronge: return "stronge";
    case RestitutionLaw::kPoisson: return "poisson";
    case RestitutionLaw::kNewton: return "newton";
  }
  return "unknown";
}

std::string_view to_string(MicrocollisionRule rule) {
  switch (rule) {
    case MicrocollisionRule::kDriftFree: return "drift_free";
    case MicrocollisionRule::kReversal: return "reversal";
  }
  return "unknown";
}

std::string_view to_string(ContactModel model) {
  switch (model) {
    case ContactModel::kPersistent: return "persistent";
    case ContactModel::kMicrocollisions: return "microcollisions";
  }
  return "unknown";
}

}  // namespace palpable
