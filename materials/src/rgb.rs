//! Linear RGB values and their luminance.

use std::ops::{Add, Mul};

/// A linear-sRGB triple (Rec. 709 primaries).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Rgb(pub [f64; 3]);

impl Rgb {
    /// Black.
    pub const ZERO: Rgb = Rgb([0.0; 3]);

    /// All three channels equal to `v`.
    pub const fn splat(v: f64) -> Self {
        Rgb([v, v, v])
    }

    /// Luminance `Y` of linear Rec. 709 RGB: `0.2126 R + 0.7152 G + 0.0722 B`.
    pub fn luminance(self) -> f64 {
        luminance(self.0)
    }

    /// Channel-wise product.
    pub fn mul_rgb(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] * o.0[0], self.0[1] * o.0[1], self.0[2] * o.0[2]])
    }

    /// Largest channel.
    pub fn max_channel(self) -> f64 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }

    /// True when every channel is finite.
    pub fn is_finite(self) -> bool {
        self.0.iter().all(|c| c.is_finite())
    }
}

/// Luminance of linear Rec. 709 RGB (the `Y` row of the sRGB -> XYZ matrix).
pub fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

impl Add for Rgb {
    type Output = Rgb;
    fn add(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}

impl Mul<f64> for Rgb {
    type Output = Rgb;
    fn mul(self, s: f64) -> Rgb {
        Rgb([self.0[0] * s, self.0[1] * s, self.0[2] * s])
    }
}
