// The registry of the fatigue laws (000, 003, 004) and phase III criteria (000 Eq. 7-12).
#include "solver/fatigue/law_registry.h"

#include <array>
#include <stdexcept>

namespace peritwin::fatigue {

namespace {

// The energy law (000 Sec. 4) takes the strain law's A_i, m_i (000 Eq. 44-46), so its reader.
constexpr std::array kLaws = {
    // 000 Eq. 14-20
    LawEntry{.name = "strain_range",
             .law = FatigueLaw::strain_range,
             .read = &read_strain_range,
             .static_failure = true,
             .damage_based = false,
             .calibrated_a2 = true,
             .scatter_band = true},
    // 000 Eq. 30-46
    LawEntry{.name = "energy",
             .law = FatigueLaw::energy,
             .read = &read_strain_range,
             .static_failure = true,
             .damage_based = false,
             .calibrated_a2 = true,
             .scatter_band = true},
    // 003 Eq. 27-50
    LawEntry{.name = "bilinear",
             .law = FatigueLaw::bilinear,
             .read = &read_bilinear,
             .static_failure = false,
             .damage_based = true,
             .calibrated_a2 = false,
             .scatter_band = true},
    // 004 Eq. 12-16
    LawEntry{.name = "kinetic",
             .law = FatigueLaw::kinetic,
             .read = &read_kinetic,
             .static_failure = true,
             .damage_based = false,
             .calibrated_a2 = false,
             .scatter_band = false},
};

constexpr std::array kStaticFailures = {
    StaticFailureEntry{"critical_stretch", StaticFailure::critical_stretch},  // 000 Eq. 7-8
    StaticFailureEntry{"critical_bond_energy",
                       StaticFailure::critical_bond_energy},  // 000 Eq. 9-12
};

}  // namespace

std::span<const LawEntry> fatigue_laws() { return kLaws; }

const LawEntry& law_entry(FatigueLaw law) {
  for (const LawEntry& e : kLaws) {
    if (e.law == law) return e;
  }
  throw std::logic_error("law_entry: a FatigueLaw without a registry line");
}

std::string_view law_name(FatigueLaw law) { return law_entry(law).name; }

std::span<const StaticFailureEntry> static_failures() { return kStaticFailures; }

}  // namespace peritwin::fatigue
