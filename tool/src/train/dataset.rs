//! Training pairs as the trainer uses them: `wi` and the flow point `x1` of `wo`, with
//! the encodings of `wi` computed once.

use super::features::{base_encoding, velocity_encoding, BASE_ENC, VEL_ENC};
use crate::data::{exact_pairs, exact_pairs_uniform_angle, Band, ExactConfig, Pair};
use crate::material::Material;
use diffbsdf::Domain;

/// Anything that yields training pairs `(wi, x1)` for a domain.
pub trait TrainingData {
    /// `(wi, x1)` pairs; `x1` in the domain's coordinates.
    fn pairs(&self) -> Vec<([f32; 3], [f32; 2])>;

    /// True when the pairs are in the incident frame of an isotropic model (every `wi` at
    /// `phi = 0`); the fitted model then turns `wi` the same way.
    fn isotropic(&self) -> bool {
        false
    }
}

/// Pairs with their `wi` encodings.
#[derive(Clone, Debug)]
pub struct TrainingSet {
    /// The flow domain.
    pub domain: Domain,
    /// Incident directions.
    pub wi: Vec<[f32; 3]>,
    /// Velocity-net encodings of `wi`.
    pub enc: Vec<[f32; VEL_ENC]>,
    /// Base-net encodings of `wi`.
    pub base_enc: Vec<[f32; BASE_ENC]>,
    /// Targets `x1`.
    pub x1: Vec<[f32; 2]>,
    /// The pairs are in the incident frame (see [`TrainingData::isotropic`]).
    pub isotropic: bool,
}

impl TrainingSet {
    /// From `(wi, x1)` pairs; drops non-finite ones.
    pub fn new(domain: Domain, pairs: &[([f32; 3], [f32; 2])]) -> Self {
        let mut set = TrainingSet {
            domain,
            wi: Vec::with_capacity(pairs.len()),
            enc: Vec::with_capacity(pairs.len()),
            base_enc: Vec::with_capacity(pairs.len()),
            x1: Vec::with_capacity(pairs.len()),
            isotropic: false,
        };
        for &(wi, x1) in pairs {
            if wi.iter().chain(&x1).all(|v| v.is_finite()) {
                set.wi.push(wi);
                set.enc.push(velocity_encoding(wi));
                set.base_enc.push(base_encoding(wi));
                set.x1.push(x1);
            }
        }
        set
    }

    /// From the materials' pair generator.
    pub fn from_source(domain: Domain, source: &dyn TrainingData) -> Self {
        let mut set = Self::new(domain, &source.pairs());
        set.isotropic = source.isotropic();
        set
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.x1.len()
    }

    /// True when there are no pairs.
    pub fn is_empty(&self) -> bool {
        self.x1.is_empty()
    }
}

/// Pairs from a material by importance resampling of its own sampler
/// ([`crate::data::exact_pairs`]), `wi` uniform over the hemisphere (the sphere for
/// transmissive materials on the sphere domain).
#[derive(Debug)]
pub struct MaterialPairs<'a> {
    /// The material.
    pub material: &'a dyn Material,
    /// The flow domain.
    pub domain: Domain,
    /// Number of pairs.
    pub count: usize,
    /// Seed of the generator.
    pub seed: u64,
    /// Fraction of extra pairs with `wi` within 30 degrees of the horizon, where the
    /// target is hardest to learn (0 for none).
    pub grazing: f64,
    /// Turn every pair into the incident frame (for an isotropic material).
    pub isotropic: bool,
    /// Isotropic fits: fraction of `wi` drawn with `theta_i` uniform in angle (the rest
    /// uniform in solid angle).
    pub angle_fraction: f64,
}

impl TrainingData for MaterialPairs<'_> {
    fn pairs(&self) -> Vec<([f32; 3], [f32; 2])> {
        let both = self.domain == Domain::Sphere && self.material.is_transmissive();
        let data_domain = match self.domain {
            Domain::Disk => crate::data::Domain::Disk,
            Domain::Sphere => crate::data::Domain::Sphere,
        };
        let cfg = ExactConfig {
            domain: data_domain,
            candidates: 64,
            seed: self.seed,
        };
        let band = Band::split(1, both)[0];
        // Isotropic fits see theta_i alone: draw it uniform in angle, so normal incidence
        // is covered (uniform in solid angle gives theta_i the density sin(theta_i)).
        let draw = |b: Band, n: usize, cfg: &ExactConfig| {
            if self.isotropic {
                exact_pairs_uniform_angle(self.material, b, n, cfg, self.angle_fraction).pairs
            } else {
                exact_pairs(self.material, b, n, cfg).pairs
            }
        };
        let mut pairs = draw(band, self.count, &cfg);
        let extra = (self.count as f64 * self.grazing.max(0.0)) as usize;
        if extra > 0 {
            let deg = std::f64::consts::PI / 180.0;
            let mut bands = vec![Band {
                theta_min: 60.0 * deg,
                theta_max: 90.0 * deg,
            }];
            if both {
                bands.push(Band {
                    theta_min: 90.0 * deg,
                    theta_max: 120.0 * deg,
                });
            }
            for (k, b) in bands.iter().enumerate() {
                let cfg = ExactConfig {
                    seed: self.seed.wrapping_add(0x5eed_0000 + k as u64 * 0x1_0000),
                    ..cfg
                };
                pairs.extend(draw(*b, extra / bands.len(), &cfg));
            }
        }
        pairs
            .iter()
            .map(|p| {
                if self.isotropic {
                    p.in_incident_frame()
                } else {
                    *p
                }
            })
            .filter_map(|p| to_flow_pair(self.domain, &p))
            .collect()
    }

    fn isotropic(&self) -> bool {
        self.isotropic
    }
}

/// `(wi, x1)` of a material pair in f32; `None` outside the domain.
pub fn to_flow_pair(domain: Domain, p: &Pair) -> Option<([f32; 3], [f32; 2])> {
    let wi = [p.wi.x as f32, p.wi.y as f32, p.wi.z as f32];
    let x1 = match domain {
        Domain::Disk => {
            if !(p.wo.z > 0.0) {
                return None;
            }
            let d = p.disk();
            [d[0] as f32, d[1] as f32]
        }
        Domain::Sphere => {
            let s = p.sphere();
            [s[0] as f32, s[1] as f32]
        }
    };
    Some((wi, x1))
}
