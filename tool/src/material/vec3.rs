//! A small `f64` 3-vector for reference computations in the local shading frame
//! (z = surface normal).

use std::ops::{Add, Mul, Neg, Sub};

/// A 3-vector of `f64` in the local shading frame (z = normal).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Vec3 {
    /// Tangent component.
    pub x: f64,
    /// Bitangent component.
    pub y: f64,
    /// Normal component.
    pub z: f64,
}

impl Vec3 {
    /// The surface normal `(0, 0, 1)`.
    pub const Z: Vec3 = Vec3 {
        x: 0.0,
        y: 0.0,
        z: 1.0,
    };

    /// Builds a vector from its components.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    /// Unit vector from spherical angles: `theta` from +z, `phi` from +x.
    pub fn from_spherical(theta: f64, phi: f64) -> Self {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        Self::new(st * cp, st * sp, ct)
    }

    /// Dot product.
    pub fn dot(self, o: Vec3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared Euclidean length.
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean length.
    pub fn length(self) -> f64 {
        self.length_squared().sqrt()
    }

    /// Unit vector in the same direction, or `None` for a zero or non-finite vector.
    pub fn try_normalize(self) -> Option<Vec3> {
        let l = self.length();
        if l > 0.0 && l.is_finite() {
            Some(self * (1.0 / l))
        } else {
            None
        }
    }

    /// True when every component is finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Mirror reflection of `self` (pointing away) about the unit normal `m`: `2 (w·m) m - w`.
    pub fn reflect(self, m: Vec3) -> Vec3 {
        m * (2.0 * self.dot(m)) - self
    }

    /// Polar angle `theta` in `[0, pi]` (from +z); assumes a unit vector.
    pub fn theta(self) -> f64 {
        self.z.clamp(-1.0, 1.0).acos()
    }

    /// Azimuth `phi` in `(-pi, pi]`.
    pub fn phi(self) -> f64 {
        self.y.atan2(self.x)
    }

    /// Rotates about the z axis by `angle` (radians).
    pub fn rotate_z(self, angle: f64) -> Vec3 {
        let (s, c) = angle.sin_cos();
        Vec3::new(c * self.x - s * self.y, s * self.x + c * self.y, self.z)
    }

    /// Components as an array.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl From<[f64; 3]> for Vec3 {
    fn from(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f64> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

/// An orthonormal frame whose third axis is a given unit vector (Duff et al. 2017).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// The axis.
    pub n: Vec3,
}

impl Frame {
    /// Frame around the unit vector `n` ("Building an orthonormal basis, revisited", 2017).
    pub fn from_z(n: Vec3) -> Self {
        let sign = 1.0_f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// Local coordinates -> world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// World -> local coordinates.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}
