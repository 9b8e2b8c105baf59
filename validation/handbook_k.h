// Handbook stress intensity factors for through cracks at a central circular hole in a plate
// under remote uniform tension σ (mode I, cracks perpendicular to the load), for checking the
// K_I that peritwin computes at crack tips growing from a hole. Units: SI (m, Pa, Pa·√m).
//
// K = σ·√(π·c)·F(c/R)·f_w, c = crack length measured from the hole edge, R = hole radius, W =
// plate width across the cracks. F is the infinite-plate (Bowie-type) factor, f_w the finite-width
// correction of Newman & Raju. Sources, what each was read from and what could not be found:
// docs/handbook-k.md.
#pragma once

namespace peritwin::validation {

/// Newman's variable λ = R/(R + c) = 1/(1 + c/R): 1 for a vanishing crack, → 0 for a long one.
double newman_lambda(double c_over_r);

/// Two equal cracks (one at each side of the hole), infinite plate: the fourth-order fit in λ
/// used by Newman & Raju (NASA TM-85793, 1984; also ch. 9 of Atluri (ed.), Computational Methods
/// in the Mechanics of Fracture, 1986) as the numerator of their hole function g2 for cracks at a
/// hole: F = 1 + 0.358λ + 1.425λ² − 1.578λ³ + 2.156λ⁴. Read from two public transcriptions of
/// those equations, not from the report; no stated accuracy was found (docs/handbook-k.md).
/// Checks: F(0) = 3.361 (≈ 3·1.1215, the edge crack at K_t = 3), F → 1 + O(λ) as c/R → ∞ (the
/// centre crack of half length R + c gives √((R+c)/c)); within 1.4 % of the Paul–Lombardo fit to
/// Bowie (1956) for 0.05 ≤ c/R ≤ 3. Valid for any c/R ≥ 0.
double bowie_factor_two_cracks(double c_over_r);

/// One crack, infinite plate: F = 0.7071 + 0.7548λ + 0.3415λ² + 0.6420λ³ + 0.9196λ⁴, the single
/// through crack at a hole of the USAF Damage Tolerant Design Handbook (AFGROW DTDHandbook,
/// Sec. 11.3, eq. 2.12), read from a public transcription; no stated accuracy found. Checks: F(0) =
/// 3.365, F → 0.7071 = 1/√2 as c/R → ∞ (the centre crack of half length R + c/2 gives
/// √((2R+c)/(2c))); within 2.3 % of the Paul–Lombardo fit to Bowie for 0.05 ≤ c/R ≤ 3.
double bowie_factor_one_crack(double c_over_r);

/// The rational fits to Bowie's (1956) infinite-plate values in the DSTO CRKGRW manual (J. Paul,
/// D. Lombardo, 1988), as carried by DSTO's easigrow (beta.rs, "dsht-bowie56"/"ssht-bowie56"):
/// two cracks 0.9439 + 0.6865/(0.2772 + c/R), one crack 0.6762 + 0.8734/(0.3246 + c/R). An
/// independent check of the two functions above for moderate c/R; their limits as c/R → ∞ (0.944
/// and 0.676 instead of 1 and 1/√2) show they are not meant for long cracks.
double bowie_fit_paul_lombardo_two_cracks(double c_over_r);
double bowie_fit_paul_lombardo_one_crack(double c_over_r);

/// Finite-width correction of Newman & Raju (TM-85793) for n cracks at a central hole of radius
/// R in a plate of width W = 2b, through-thickness form (a/t = 1):
///   f_w = √( sec(πR/W) · sec(π(2R + n·c) / (4(b − c) + 2n·c)) ),  n = 2 or 1,
/// i.e. √(sec(πR/W)·sec(π(R+c)/W)) for two cracks and √(sec(πR/W)·sec(π(R+c/2)/(W−c))) for one,
/// the forms of DTD Handbook Sec. 11.3 eq. 2.11/2.12. → 1 as W → ∞; with R → 0 and two cracks it
/// is Feddersen's √sec(πc/W) for a centre crack of half length c. Requires R + c < W/2 (tip
/// inside the plate). The handbook's further factor F_ww is left out (docs/handbook-k.md: below
/// 1e-3 for the strip of the brief).
double finite_width_factor_hole_cracks(double width, double hole_radius, double crack_length,
                                       bool two_cracks);

/// K_I at the tip of a crack of length c from the edge of a central hole, remote tension σ:
/// σ·√(π·c)·F(c/R)·f_w with F = bowie_factor_two_cracks or bowie_factor_one_crack. Throws
/// std::invalid_argument for R ≤ 0, c ≤ 0, W ≤ 0 or R + c ≥ W/2.
double k_crack_at_hole(double sigma, double width, double hole_radius, double crack_length,
                       bool two_cracks);

}  // namespace peritwin::validation
