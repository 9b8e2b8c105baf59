// The fatigue laws and phase III criteria by their configuration names: one line per law (its
// name, its FatigueLaw, its config reader in solver/fatigue/laws/) and one per criterion. A new law
// is a file under solver/fatigue/laws/ and a line in law_registry.cpp.
#pragma once

#include <span>
#include <string_view>

#include "core/param_reader.h"
#include "solver/fatigue/fatigue_settings.h"

namespace peritwin::fatigue {

struct LawEntry {
  std::string_view name;  ///< `law = "..."` of the configuration's fatigue table
  FatigueLaw law;
  /// Reads the law's keys of the fatigue table into the settings (bounds checked, errors reported).
  void (*read)(core::ParamReader& r, FatigueSettings& f);
  /// Whether a phase III criterion (000 Eq. 7-12, `static_failure`) applies: false for the
  /// bilinear law (003), whose sc plays that role.
  bool static_failure;
  /// Bonds carry a damage variable (003 Eq. 13-15) instead of a remaining life: the engine's
  /// damage mode, bond-based models only, softening bonds (PCG), no fork of the live engine.
  bool damage_based;
  /// The law has the phase-II coefficient A2 that 000 App. A calibrates (000 Eq. 27), so a coarser
  /// estimate model can be calibrated to the detail's grid.
  bool calibrated_a2;
  /// Remaining life gets the A2-scatter band (three simulations); not for the kinetic law (004),
  /// whose constants are physical (U, ω0), not a fitted A2.
  bool scatter_band;
};

struct StaticFailureEntry {
  std::string_view name;  ///< `static_failure = "..."`
  StaticFailure criterion;
};

/// Every law, in the order the configuration's error messages list them.
std::span<const LawEntry> fatigue_laws();
/// The entry of `law` (every FatigueLaw has one).
const LawEntry& law_entry(FatigueLaw law);
/// The name of `law` in the configuration ("strain_range", ...).
std::string_view law_name(FatigueLaw law);
/// Every phase III criterion: critical_stretch (000 Eq. 7-8), critical_bond_energy (000 Eq. 9-12).
std::span<const StaticFailureEntry> static_failures();

}  // namespace peritwin::fatigue
