//! The specification: every constant that the kernel, the generated GLSL / WGSL / C, the
//! trainer and the tests must agree on, in one place.
//!
//! The kernel computes with these values; the code generator prints them into the code it
//! emits; the trainer and the tests read them. Nothing outside this module writes one of
//! them again. `docs/math.md` defines where each one enters the model.
//!
//! A renderer never needs this module: it is public so that other implementations (the
//! generated code, a port) can be checked against the kernel.

// ---------------------------------------------------------------------------------------
// Network shapes
// ---------------------------------------------------------------------------------------

/// Flow-state features the velocity net's first layer has columns for: `(x, y, 0)` on the
/// disk (2 used), `(theta, sin phi, cos phi)` on the sphere (3 used).
pub const MAX_FEATURES: usize = 3;

/// Outputs of the base net: two location and two log-scale parameters
/// (`docs/math.md`, "Base distribution").
pub const BASE_OUTPUTS: usize = 4;

/// Outputs of the velocity net: the velocity `v = (v_0, v_1)` in flow coordinates.
pub const VELOCITY_OUTPUTS: usize = 2;

/// Inputs of the `wi` encoding that are the raw direction (`wi.x, wi.y, wi.z`).
pub const ENCODING_RAW: usize = 3;

/// Sine-cosine pairs per axis and frequency in the `wi` encoding (one sine, one cosine per
/// axis: `6 = 2 * 3` values per frequency).
pub const ENCODING_PER_FREQ: usize = 6;

/// Largest hidden width a blob may declare (keeps every size computation far from
/// overflow).
pub const MAX_WIDTH: u16 = 1024;
/// Largest number of hidden layers a blob may declare.
pub const MAX_LAYERS: u8 = 16;
/// Largest number of encoding frequencies a blob may declare.
pub const MAX_FREQS: u8 = 16;

// ---------------------------------------------------------------------------------------
// Steps
// ---------------------------------------------------------------------------------------

/// `steps = DEFAULT_STEPS` in a call means the model's own default step count, in every
/// language (Rust, the C ABI, the generated C, GLSL and WGSL).
pub const DEFAULT_STEPS: u32 = 0;
/// What a sampling call returns in C (the C ABI and the generated C header alike) when it
/// produced a sample.
pub const STATUS_OK: i32 = 0;
/// What a sampling call returns in C when it produced no sample (invalid input, or the
/// sample left the domain); its outputs are then zero.
pub const STATUS_NO_SAMPLE: i32 = 1;

/// Samples the batch calls without a PDF ([`crate::Model::sample_direction_batch`]) run
/// through the flow together, one per lane of each dense layer's multiply-adds: every
/// sample's arithmetic is the one of a call alone (bit for bit); what changes is that the
/// lanes' independent sums overlap in the multiply-add pipeline (docs/performance.md,
/// "Samples in lanes").
pub const BATCH_LANES: usize = 8;

/// Partial sums of the readout's dot products (kernel) and of the trainer's: sum `l` takes
/// the inputs `i = l (mod DOT_PARTIAL_SUMS)` in order, and the sums are added as
/// `((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7))`. Lets a dot product vectorise
/// without reassociating floats; the trainer's passes rely on this order for their bits.
pub const DOT_PARTIAL_SUMS: usize = 8;

/// Whether the networks' multiply-adds (the dense layers, their tangents and the
/// readout's dot products) are fused, rounded once: true in a kernel built with the `fma`
/// feature, false by default (a product and a sum, each rounded). Generated code made
/// with `fused` set to this value computes them the same way.
pub const FUSED_MULTIPLY_ADD: bool = cfg!(feature = "fma");

/// Most Euler steps a call may ask for, and a blob may declare as its default: bounds the
/// work of one call (a larger count gives an invalid result, a blob declaring one is
/// rejected). Trained models use 1 to 16.
pub const MAX_STEPS: u32 = 256;

// ---------------------------------------------------------------------------------------
// Activation: SiLU with the kernel's polynomial exp
// ---------------------------------------------------------------------------------------

/// `exp_poly(x)` clamps `x` to `[EXP_ARG_MIN, EXP_ARG_MAX]` (f32: `e^x` stays normal).
pub const EXP_ARG_MIN: f32 = -87.0;
/// Upper clamp of `exp_poly`'s argument.
pub const EXP_ARG_MAX: f32 = 88.0;
/// Clamp of the sigmoid's exponent in f16 shaders: `e^11 < 65504` (moves sigmoid < 2e-5).
pub const EXP_ARG_LIMIT_F16: f32 = 11.0;
/// `ln 2` split into a part exact in f32 and the remainder (Cody-Waite reduction).
pub const LN2_HI: f32 = 0.693_145_75;
/// The remainder of `ln 2 - LN2_HI`.
pub const LN2_LO: f32 = 1.428_606_8e-6;
/// `1.5 * 2^23`: adding and subtracting it rounds an f32 of magnitude `< 2^22` to the
/// nearest integer without a branch.
pub const ROUND_MAGIC: f32 = 12_582_912.0;

// ---------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------

/// A direction is accepted when `| |w|^2 - 1 | <= UNIT_TOLERANCE` (and then normalised).
pub const UNIT_TOLERANCE: f32 = 1e-3;

/// The half-vector chart takes the part of `s = wi + wo` along `wi`'s azimuth from the
/// unit-vector identity (`docs/math.md`, (58)) where `wo`'s part along it, `t`, is negative
/// and `rho - t` (`rho = |wi.xy|`) exceeds this: there the plain sum cancels and the
/// identity's error (about the rounding of `wo` over `rho - t`) is the smaller one.
pub const HALF_VECTOR_IDENTITY_SPAN: f32 = 1.0;

/// Below this `|wi.xy|`, `wi` is the normal and the incident frame of an isotropic model is
/// the identity.
pub const NORMAL_INCIDENCE_RHO: f32 = 1e-12;

// ---------------------------------------------------------------------------------------
// Base distributions
// ---------------------------------------------------------------------------------------

/// Sharpest scale a base distribution may have: `ln(1e-4)` (sigma or gamma).
pub const LN_SCALE_MIN: f32 = -9.210_34;
/// Widest scale: `ln(10)`.
pub const LN_SCALE_MAX: f32 = core::f32::consts::LN_10;

/// Smallest tail probability the normal quantile is evaluated at (`2^-40`): `u` closer
/// than this to 0 or 1 maps to `|z| = 7.1`.
pub const GAUSSIAN_TAIL_MIN: f32 = 9.094_947e-13;

/// `K` of the compressive warp of the standard coordinates, `y = K asinh(z / K)`
/// (docs/math.md, §6.4; `ModelDef::standard_warp`): the identity for `|z| << K`,
/// logarithmic beyond. Measured on the RGL files with K = 3 (docs/measured-materials.md,
/// "A compressive warp of the standard coordinates").
pub const STANDARD_WARP_K: f32 = 3.0;

/// The standard normal CDF `Phi(z) = erfc(-z / sqrt 2) / 2` (docs/math.md, (73)), by the
/// Chebyshev fit of `erfc` in Press et al., "Numerical Recipes" (2nd ed., §6.2, `erfcc`):
/// `erfc(x) = t exp(-x^2 + P(t))`, `t = 1 / (1 + x/2)`, `x >= 0`, fractional error below
/// 1.2e-7. `P`'s coefficients, highest degree first.
pub const ERFC_POLY: [f32; 10] = [
    0.170_872_77,
    -0.822_152_23,
    1.488_515_9,
    -1.135_204,
    0.278_868_07,
    -0.186_288_06,
    0.096_784_18,
    0.374_091_96,
    1.000_023_7,
    -1.265_512_2,
];

// ---------------------------------------------------------------------------------------
// The latent table (docs/math.md, §6.5; `ModelDef::latent_table`)
// ---------------------------------------------------------------------------------------

/// Cells per side of the latent table's grid on `[0, 1]^2` where the blob stores its nodes
/// as 8-bit codes (blob flag bit 5; [`crate::base::table::TableGrid::Codes`], the grid the
/// trainer fits); the bilinear density has `(LATENT_TABLE_CELLS + 1)^2` nodes per slice.
pub const LATENT_TABLE_CELLS: usize = 32;

/// Cells per side of a latent table whose nodes the blob stores as values of its precision
/// (flag bit 4 without bit 5, [`crate::base::table::TableGrid::Values`]: the blobs written
/// before the coded table).
pub const LATENT_TABLE_VALUE_CELLS: usize = 16;

/// Incidence slices of the latent table (blob flag bit 7 clear), at `s = 1 - sqrt(wi.z)`
/// evenly spaced on `[0, 1]` (dense towards grazing incidence, where the target changes
/// fastest); a `wi` between two slices mixes their densities linearly.
pub const LATENT_TABLE_SLICES: usize = 32;

/// Incidence slices of a latent table on the blended layout (blob flag bit 7,
/// [`crate::base::table::TableGrid::BlendedSlices`], what the trainer writes): at `s = x (b +
/// (1 - b) x)`, `x = sqrt(1 - sqrt(wi.z))`, `b` = [`LATENT_TABLE_SLICE_BLEND`], evenly spaced
/// on `[0, 1]` (docs/math.md, (82)): near normal incidence `s` grows like `theta_i` (a slice
/// every 5-6 degrees there, where the flow's weight changes fastest with `theta_i`), towards
/// grazing as densely as the 32 slices of [`LATENT_TABLE_SLICES`] (about a degree apart).
pub const LATENT_TABLE_BLENDED_SLICES: usize = 40;

/// The share `b` of the blended layout's term linear in `x` (docs/math.md, (82)).
pub const LATENT_TABLE_SLICE_BLEND: f32 = 0.5;

/// The most slices a latent table has.
pub const LATENT_TABLE_MAX_SLICES: usize = LATENT_TABLE_BLENDED_SLICES;

/// Largest node value a latent table may hold (a blob or parameter vector with a value
/// outside `(0, LATENT_TABLE_VALUE_MAX]` is refused): the sums over a slice stay far from
/// overflow and every cell's density positive.
pub const LATENT_TABLE_VALUE_MAX: f32 = 1e6;

/// Codes per doubling of a coded table's node value: code `c` stands for
/// `2^((c - LATENT_TABLE_CODE_ONE) / LATENT_TABLE_CODE_STEPS)` (docs/math.md, (79)), a
/// 4.4 % step, below what the fit resolves (docs/measured-materials.md, "A finer table in
/// 8-bit codes").
pub const LATENT_TABLE_CODE_STEPS: u8 = 16;

/// The code of node value 1. Code 0 is refused (a zeroed table section is not a table), so
/// codes span `2^(-79/16)` = 0.032 to `2^(175/16)` = 1 966: a slice normalised to integral
/// 1 with its 5 % uniform share has every node at least 0.05.
pub const LATENT_TABLE_CODE_ONE: u8 = 80;

/// `2^(r / 16)`, `r = 0..16`, rounded to f32: code `c` with `c - LATENT_TABLE_CODE_ONE = 16
/// q + r` (`0 <= r < 16`) has the value `LATENT_TABLE_CODE_FRACTIONS[r] * 2^q`, a product
/// by a power of two, exact in every language.
pub const LATENT_TABLE_CODE_FRACTIONS: [f32; 16] = [
    1.0,
    1.044_273_7,
    1.090_507_7,
    1.138_788_6,
    1.189_207_1,
    1.241_857_8,
    1.296_839_6,
    1.354_255_6,
    core::f32::consts::SQRT_2,
    1.476_826_2,
    1.542_210_8,
    1.610_490_3,
    1.681_792_9,
    1.756_252_2,
    1.834_008_1,
    1.915_206_6,
];

/// `ln(1/sqrt(2 pi))`, the normal log-density's constant.
pub const LN_INV_SQRT_2PI: f32 = -0.918_938_5;

/// `ln(4 pi)`, the wrapped Cauchy log-density's constant.
pub const LN_4PI: f32 = 2.531_024_3;

/// Giles' single-precision erfinv: the central branch is taken while
/// `w = -ln(4 q (1 - q)) < ERFINV_BRANCH_W`.
pub const ERFINV_BRANCH_W: f32 = 5.0;
/// The central branch's polynomial is in `w - ERFINV_CENTRAL_SHIFT`.
pub const ERFINV_CENTRAL_SHIFT: f32 = 2.5;
/// Central-branch coefficients, highest degree first (Horner: `p = c[0]`, then
/// `p = c[k] + p * w`).
pub const ERFINV_CENTRAL: [f32; 9] = [
    2.810_226_4e-8,
    3.432_739_4e-7,
    -3.523_387_7e-6,
    -4.391_506_5e-6,
    2.185_808_7e-4,
    -1.253_725e-3,
    -4.177_681_6e-3,
    0.246_640_73,
    1.501_409_4,
];
/// The tail branch's polynomial is in `sqrt(w) - ERFINV_TAIL_SHIFT`.
pub const ERFINV_TAIL_SHIFT: f32 = 3.0;
/// Tail-branch coefficients, highest degree first.
pub const ERFINV_TAIL: [f32; 9] = [
    -2.002_142_6e-4,
    1.009_505_6e-4,
    1.349_343_2e-3,
    -3.673_428_4e-3,
    5.739_507_7e-3,
    -7.622_461_3e-3,
    9.438_870_5e-3,
    1.001_674,
    2.832_976_8,
];

// ---------------------------------------------------------------------------------------
// The exact inverse (Newton on each Euler step)
// ---------------------------------------------------------------------------------------

/// Newton iterations before a step is declared not invertible (typically 2 to 4 are used).
pub const NEWTON_MAX_ITERS: u32 = 32;
/// Halvings of a Newton step's length before it is taken anyway.
pub const LINE_SEARCH_HALVINGS: u32 = 8;
/// Newton stops when the update is below `NEWTON_TOL * (1 + |x|)` (max norm); f32 noise in
/// `x + h v(x)` sits near 3e-7 of that scale.
pub const NEWTON_TOL: f32 = 1e-6;
/// Where Newton's last update is at most `DET_REUSE_TOL * (1 + |x|)` (max norm), about one
/// f32 rounding of `x`, the returned point's determinant and velocity are the ones at the
/// iterate it was updated from, not evaluated again: one Jacobian evaluation fewer per step
/// on most steps (`pdf()` 1.2-1.4x faster), PDFs as close to the forward pass's as before
/// (docs/math.md, "Determinant at the returned point").
pub const DET_REUSE_TOL: f32 = 1e-7;
/// Where Newton has converged and the determinant's change over its last update,
/// extrapolated from its change over the step before (`|det - det_prev| / det` times the
/// ratio of the two lengths), is at most `DET_SECANT_TOL`, the determinant at the iterate
/// stands for the returned point's as under [`DET_REUSE_TOL`]: about 10 % fewer Jacobian
/// evaluations in `pdf()` on the shipped models, within float noise of the forward pass's
/// PDF (docs/math.md, "Determinant at the returned point").
pub const DET_SECANT_TOL: f32 = 1e-6;
/// `sample` reports the density at the flow point `pdf` reads for the returned (f32) `wo`:
/// its start point is moved by `M^-1 (end - x_N)` (docs/math.md, (71)), and where that
/// moves it by more than `RETURNED_START_TOL * (1 + |x0|)` (max norm) the determinants are
/// taken again along the moved trajectory (72). Below it the determinants' change is well
/// under float precision; above it (a few samples in 10^4 on most shipped models, 8 % of
/// the iridescent paint's half-vector model, whose flow compresses most) one more pass.
pub const RETURNED_START_TOL: f32 = 3e-6;
/// Newton tolerance of the generated f16 inverse: an f16 velocity is a step function of
/// `x` at about 1e-3 of its size, so [`NEWTON_TOL`] cannot be reached there.
pub const NEWTON_TOL_F16: f32 = 2e-3;

// ---------------------------------------------------------------------------------------
// Exactness checks (tests, `fit`, `eval`)
// ---------------------------------------------------------------------------------------

/// Largest relative difference between `pdf(wi, wo)` and the PDF `sample` reported with
/// `wo`, where f32 rounding allows it (see [`PDF_ROUNDING_SPAN`]).
pub const PDF_CONSISTENCY_TOL: f32 = 1e-4;
/// Where the density changes by more than [`PDF_CONSISTENCY_TOL`] within a few f32
/// roundings (sharply compressing flows, the far tails of a sharp base), the difference may
/// reach this many times the density's relative change over one machine epsilon of `wo` or
/// of the start point `x0` (`Diagnostics::pdf_rounding`): one rounding per Euler step and
/// the incident-frame rotation.
pub const PDF_ROUNDING_SPAN: f32 = 32.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_ln2_sums_to_ln2() {
        let sum = LN2_HI as f64 + LN2_LO as f64;
        assert!((sum - core::f64::consts::LN_2).abs() < 1e-12);
    }

    #[test]
    fn log_constants_match_their_definitions() {
        let pi = core::f64::consts::PI;
        assert!((LN_INV_SQRT_2PI as f64 + 0.5 * libm::log(2.0 * pi)).abs() < 1e-7);
        assert!((LN_4PI as f64 - libm::log(4.0 * pi)).abs() < 1e-6);
        assert!((LN_SCALE_MIN as f64 - libm::log(1e-4)).abs() < 1e-5);
        assert_eq!(GAUSSIAN_TAIL_MIN, 1.0 / (1u64 << 40) as f32);
    }

    #[test]
    fn code_fractions_are_the_f32_roots_of_two() {
        for (r, &f) in LATENT_TABLE_CODE_FRACTIONS.iter().enumerate() {
            let exact = libm::exp2(r as f64 / f64::from(LATENT_TABLE_CODE_STEPS));
            assert_eq!(f, exact as f32, "r = {r}");
        }
    }
}
