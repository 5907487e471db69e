//! SiLU and its derivative, written out for the hand-derived Jacobian.

use crate::math::exp_poly;

/// `sigmoid(z) = 1 / (1 + e^-z)`.
#[inline(always)]
pub fn sigmoid(z: f32) -> f32 {
    1.0 / (1.0 + exp_poly(-z))
}

/// `silu(z) = z * sigmoid(z)`.
#[inline(always)]
pub fn silu(z: f32) -> f32 {
    z * sigmoid(z)
}

/// `(silu(z), silu'(z))` with `silu'(z) = s * (1 + z * (1 - s))`, `s = sigmoid(z)`.
#[inline(always)]
pub fn silu_with_slope(z: f32) -> (f32, f32) {
    let s = sigmoid(z);
    (z * s, s * (1.0 + z * (1.0 - s)))
}

/// Applies SiLU to a layer in place.
#[inline(always)]
pub(crate) fn silu_layer<const N: usize>(z: &mut [f32; N]) {
    for v in z.iter_mut() {
        *v = silu(*v);
    }
}

/// Applies SiLU to a layer in place and scales its two tangents by the slope.
#[inline(always)]
pub(crate) fn silu_layer_tangents<const N: usize>(z: &mut [f32; N], dz: &mut [[f32; N]; 2]) {
    for i in 0..N {
        let (h, slope) = silu_with_slope(z[i]);
        z[i] = h;
        dz[0][i] *= slope;
        dz[1][i] *= slope;
    }
}
