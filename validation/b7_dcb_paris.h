// B7 (issue 36): the DCB of 003 Sec. 6.6 (after Juntti et al. 1999) under opposing end moments
// with the third degradation law: the Paris plot dX/dN against G/G_c over a range of moments, its
// slope and intercept against the law's parameters, and the constant growth rate at constant
// moment that pure-moment loading gives (G independent of the crack length, 003 Eq. 56).
#pragma once

#include <string>

#include "validation/b6_dcb.h"

namespace peritwin::validation {

/// B7's DCB: L = 0.15 m, arms 3.1 mm (H = 6.2 mm), B = 20 mm, E = 120 GPa, a = 35 mm, plane strain,
/// G_c = 260 J/m², k_r = 4.38 (003 Sec. 6.6). Bond-based plane strain fixes ν = 1/4 (003 Sec. 6.1),
/// not the specimen's 0.3. `ligament` shortens the modelled length to a + ligament: under pure
/// moments the uncracked part carries no load beyond a few H from the tip (Eq. 56 has no L), and
/// the full 115 mm ligament would double the nodes for nothing (dcb_compliance_energy_release_rate
/// measures G on the shortened model).
DcbSpec b7_spec(double horizon_ratio, int rows_per_arm, double ligament = 0.040);

/// 003 Table 4 is lost. The third law's exponent m = 4 (003 Sec. 6.6-6.7); the Paris exponent it
/// predicts in G is m/2 = 2 (the bond stretches near the tip scale as √G, the fatigue zone's size
/// does not depend on G while the static part is negligible, so dX/dN ∝ A G^{m/2}); A is fixed so
/// that the growth is steady within a few hundred increments.
fatigue::BilinearParams b7_law();

/// peritwin-validate --case B7: JSON lines and a PNG of the Paris plot into out_dir.
/// `only_ratio` > 0: that G/G_c alone.
int run_b7(const std::string& out_dir, bool quick, double only_ratio = 0.0);

}  // namespace peritwin::validation
