#include "core/settings.hpp"

#include <cstdio>
#include <cstdlib>
#include <limits>

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

namespace {

// Reads a number (an integer written in a scene counts) for the checks below.
std::optional<double> as_number(const SettingValue& v) {
  if (const double* x = std::get_if<double>(&v)) return *x;
  if (const long long* i = std::get_if<long long>(&v)) return static_cast<double>(*i);
  return std::nullopt;
}

// A number in [lo, hi] (lo excluded when `open_lo`), finite.
bool number_in(const SettingValue& v, double lo, double hi, bool open_lo, double& out) {
  const std::optional<double> x = as_number(v);
  if (!x || !std::isfinite(*x) || *x > hi || *x < lo || (open_lo && *x == lo)) return false;
  out = *x;
  return true;
}

bool integer_in(const SettingValue& v, long long lo, long long hi, int& out) {
  const long long* i = std::get_if<long long>(&v);
  if (i == nullptr || *i < lo || *i > hi) return false;
  out = static_cast<int>(*i);
  return true;
}

template <typename Enum, std::size_t N>
bool choice(const SettingValue& v, const Enum (&choices)[N], Enum& out) {
  const std::string* word = std::get_if<std::string>(&v);
  if (word == nullptr) return false;
  for (Enum c : choices) {
    if (to_string(c) == *word) {
      out = c;
      return true;
    }
  }
  return false;
}

constexpr double kHuge = std::numeric_limits<double>::max();
constexpr RestitutionLaw kLaws[] = {RestitutionLaw::kStronge, RestitutionLaw::kPoisson,
                                    RestitutionLaw::kNewton};
constexpr MicrocollisionRule kRules[] = {MicrocollisionRule::kDriftFree,
                                         MicrocollisionRule::kReversal};
constexpr ContactModel kModels[] = {ContactModel::kPersistent, ContactModel::kMicrocollisions};

std::vector<SettingInfo> make_table() {
  using V = SettingValue;
  return {
      {"envelope", "envelope_m", "m", "a positive number",
       "collision envelope: a pair closer than this and approaching collides; the main accuracy "
       "knob (error ~ envelope, events ~ 1/sqrt(envelope))",
       [](const Settings& s) { return V(s.envelope_m); },
       [](Settings& s, const V& v) { return number_in(v, 0.0, kHuge, true, s.envelope_m); }},
      {"microcollision_speed", "microcollision_speed_mps", "m/s", "a positive number or \"auto\"",
       "approach speed below which a collision is a microcollision; auto: sqrt(2 g_n envelope) "
       "per contact",
       [](const Settings& s) {
         return s.microcollision_speed_mps ? V(*s.microcollision_speed_mps) : V(std::string("auto"));
       },
       [](Settings& s, const V& v) {
         if (const std::string* w = std::get_if<std::string>(&v)) {
           if (*w != "auto") return false;
           s.microcollision_speed_mps.reset();
           return true;
         }
         double x = 0.0;
         if (!number_in(v, 0.0, kHuge, true, x)) return false;
         s.microcollision_speed_mps = x;
         return true;
       }},
      {"microcollision_speed_slack", "microcollision_speed_slack", "-", "a number in [0, 0.01]",
       "relative slack of the microcollision test: approach <= v_micro (1 + slack)",
       [](const Settings& s) { return V(s.microcollision_speed_slack); },
       [](Settings& s, const V& v) {
         return number_in(v, 0.0, 0.01, false, s.microcollision_speed_slack);
       }},
      {"integration_tolerance", "integration_tolerance", "-", "a number in [1e-15, 1)",
       "relative tolerance of the Runge-Kutta integration of a collision over p_z",
       [](const Settings& s) { return V(s.integration_tolerance); },
       [](Settings& s, const V& v) {
         double x = 0.0;
         if (!number_in(v, 1e-15, 1.0, false, x) || x == 1.0) return false;
         s.integration_tolerance = x;
         return true;
       }},
      {"restitution_law", "restitution_law", "", "\"stronge\", \"poisson\" or \"newton\"",
       "how a collision's restitution ends: energetic (Stronge), kinetic (Poisson) or kinematic "
       "(Newton, can create energy)",
       [](const Settings& s) { return V(std::string(to_string(s.restitution_law))); },
       [](Settings& s, const V& v) { return choice(v, kLaws, s.restitution_law); }},
      {"microcollision_rule", "microcollision_rule", "", "\"drift_free\" or \"reversal\"",
       "what a microcollision aims at: zero mean slip over the next flight, or Mirtich's reversal",
       [](const Settings& s) { return V(std::string(to_string(s.microcollision_rule))); },
       [](Settings& s, const V& v) { return choice(v, kRules, s.microcollision_rule); }},
      {"contact_model", "contact_model", "", "\"persistent\" or \"microcollisions\"",
       "contact that persists: held as a constraint between events, or trains of microcollisions",
       [](const Settings& s) { return V(std::string(to_string(s.contact_model))); },
       [](Settings& s, const V& v) { return choice(v, kModels, s.contact_model); }},
      {"still_speed", "still_speed_mps", "m/s", "a number >= 0",
       "relative speed below which a held contact counts as still (sticks; an island at rest)",
       [](const Settings& s) { return V(s.still_speed_mps); },
       [](Settings& s, const V& v) { return number_in(v, 0.0, kHuge, false, s.still_speed_mps); }},
      {"inertia_symmetry_tolerance", "inertia_symmetry_tolerance", "-", "a number in [0, 1e-3]",
       "relative difference of principal moments below which free flight uses the symmetric "
       "closed form",
       [](const Settings& s) { return V(s.inertia_symmetry_tolerance); },
       [](Settings& s, const V& v) {
         return number_in(v, 0.0, 1e-3, false, s.inertia_symmetry_tolerance);
       }},
      {"centre_of_pressure", "centre_of_pressure", "", "true or false",
       "face-on-face collisions act through the centre of mass while it meets the patch "
       "(microcollision model)",
       [](const Settings& s) { return V(s.centre_of_pressure); },
       [](Settings& s, const V& v) {
         const bool* b = std::get_if<bool>(&v);
         if (b == nullptr) return false;
         s.centre_of_pressure = *b;
         return true;
       }},
      {"broad_phase_horizon", "broad_phase_horizon_s", "s", "a positive number",
       "how much future flight a moving body's swept box covers before it is refreshed",
       [](const Settings& s) { return V(s.broad_phase_horizon_s); },
       [](Settings& s, const V& v) {
         return number_in(v, 0.0, kHuge, true, s.broad_phase_horizon_s);
       }},
      {"broad_phase_max_sweep", "broad_phase_max_sweep", "-", "a positive number",
       "the farthest a fast body's swept box reaches, in multiples of the body's reach",
       [](const Settings& s) { return V(s.broad_phase_max_sweep); },
       [](Settings& s, const V& v) {
         return number_in(v, 0.0, kHuge, true, s.broad_phase_max_sweep);
       }},
      {"retry_limit", "retry_limit", "", "an integer from 1 to 1000000",
       "events at one instant for one pair before a rounding loop is reported and skipped",
       [](const Settings& s) { return V(static_cast<long long>(s.retry_limit)); },
       [](Settings& s, const V& v) { return integer_in(v, 1, 1000000, s.retry_limit); }},
      {"distance_max_steps", "distance_max_steps", "", "an integer from 10 to 100000000",
       "feature steps allowed in one closest-feature query before it reports failure",
       [](const Settings& s) { return V(static_cast<long long>(s.distance_max_steps)); },
       [](Settings& s, const V& v) { return integer_in(v, 10, 100000000, s.distance_max_steps); }},
      {"toi_min_progress", "toi_min_progress_s", "s", "a number in [0, 1]",
       "least step of a conservative time-of-impact bound (raised and counted); 0: no floor",
       [](const Settings& s) { return V(s.toi_min_progress_s); },
       [](Settings& s, const V& v) { return number_in(v, 0.0, 1.0, false, s.toi_min_progress_s); }},
  };
}

}  // namespace

const std::vector<SettingInfo>& settings_table() {
  static const std::vector<SettingInfo> table = make_table();
  return table;
}

std::string format_setting(const SettingValue& value) {
  if (const bool* b = std::get_if<bool>(&value)) return *b ? "true" : "false";
  if (const long long* i = std::get_if<long long>(&value)) return std::to_string(*i);
  if (const std::string* w = std::get_if<std::string>(&value)) return "\"" + *w + "\"";
  const double x = std::get<double>(value);
  char buffer[32];
  for (int digits = 1; digits <= 17; ++digits) {  // the shortest form that reads back exactly
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
    if (std::strtod(buffer, nullptr) == x) break;
  }
  return buffer;
}

std::vector<DerivedSetting> derived_settings(const Settings& s, double gravity_mps2) {
  return {
      {"target_gap", "m", derived_target_gap(s),
       "the gap a time-of-impact bound aims at (envelope / 2)"},
      {"rider_distance", "m", derived_rider_distance(s),
       "how far apart a body resting on another still rides along (2 envelopes)"},
      {"microcollision_speed", "m/s", derived_microcollision_speed(s, gravity_mps2),
       "the microcollision speed of a contact pressed by all of gravity"},
      {"progress_floor", "s", derived_progress_floor(s, 0.0),
       "least step of a bound at t = 0 (grows as 1e-12 t past t = 1 s)"},
  };
}

}  // namespace palpable
