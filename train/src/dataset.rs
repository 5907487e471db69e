//! Training pairs as the trainer uses them: `wi` and the flow point `x1` of `wo`, with
//! the encodings of `wi` computed once.

use crate::data::{exact_pairs, exact_pairs_uniform_angle, Band, ExactConfig, Pair};
use crate::features::push_encoding;
use diffbsdf::spec::MAX_FREQS;
use diffbsdf::{encoding_len, Domain};
use diffbsdf_materials::{DVec3, IncidentFold, Material, Spherical};

/// Anything that yields training pairs `(wi, x1)` for a domain.
pub trait TrainingData {
    /// `(wi, x1)` pairs; `x1` in the domain's coordinates.
    fn pairs(&self) -> Vec<([f32; 3], [f32; 2])>;

    /// True when the pairs are in the incident frame of an isotropic model (every `wi` at
    /// `phi = 0`); the fitted model then turns `wi` the same way.
    fn isotropic(&self) -> bool {
        false
    }

    /// The fold of the incident azimuths the pairs are in (an anisotropic material's
    /// symmetry); the fitted model then folds `wi` the same way.
    fn fold(&self) -> IncidentFold {
        IncidentFold::None
    }
}

/// Pairs with their `wi` encodings.
#[derive(Clone, Debug)]
pub struct TrainingSet {
    /// The flow domain.
    pub domain: Domain,
    /// Frequencies of the stored encodings (every net with as many or fewer reads a
    /// prefix).
    pub freqs: u8,
    /// Incident directions.
    pub wi: Vec<[f32; 3]>,
    /// Encodings of `wi`, `encoding_len(freqs)` values per pair, back to back.
    enc: Vec<f32>,
    /// Targets `x1`.
    pub x1: Vec<[f32; 2]>,
    /// The pairs are in the incident frame (see [`TrainingData::isotropic`]).
    pub isotropic: bool,
    /// The pairs are folded (see [`TrainingData::fold`]).
    pub fold: IncidentFold,
    /// Start of each run of consecutive pairs with the same `wi` (bit for bit), then the
    /// number of pairs.
    run_starts: Vec<usize>,
}

impl TrainingSet {
    /// From `(wi, x1)` pairs, encoding `wi` with `freqs` frequencies (at most
    /// [`MAX_FREQS`]: the nets' largest); drops non-finite pairs.
    pub fn new(domain: Domain, freqs: u8, pairs: &[([f32; 3], [f32; 2])]) -> Self {
        let freqs = freqs.min(MAX_FREQS);
        let mut set = TrainingSet {
            domain,
            freqs,
            wi: Vec::with_capacity(pairs.len()),
            enc: Vec::with_capacity(pairs.len() * encoding_len(freqs)),
            x1: Vec::with_capacity(pairs.len()),
            isotropic: false,
            fold: IncidentFold::None,
            run_starts: Vec::new(),
        };
        for &(wi, x1) in pairs {
            if wi.iter().chain(&x1).all(|v| v.is_finite()) {
                let same =
                    |w: &[f32; 3]| w.iter().zip(&wi).all(|(a, b)| a.to_bits() == b.to_bits());
                if !set.wi.last().is_some_and(same) {
                    set.run_starts.push(set.wi.len());
                }
                set.wi.push(wi);
                push_encoding(wi, freqs, &mut set.enc);
                set.x1.push(x1);
            }
        }
        set.run_starts.push(set.wi.len());
        set
    }

    /// Number of runs of consecutive pairs that share one `wi`.
    pub fn runs(&self) -> usize {
        self.run_starts.len() - 1
    }

    /// The pairs of run `r` (`r < runs()`).
    pub fn run(&self, r: usize) -> std::ops::Range<usize> {
        self.run_starts[r]..self.run_starts[r + 1]
    }

    /// From the materials' pair generator.
    pub fn from_source(domain: Domain, freqs: u8, source: &dyn TrainingData) -> Self {
        let mut set = Self::new(domain, freqs, &source.pairs());
        set.isotropic = source.isotropic();
        set.fold = source.fold();
        set
    }

    /// The encoding of pair `i`'s `wi` with `freqs` frequencies (at most
    /// [`TrainingSet::freqs`]): a prefix of the stored one.
    pub fn encoding(&self, i: usize, freqs: u8) -> &[f32] {
        assert!(
            freqs <= self.freqs,
            "the training set holds fewer frequencies"
        );
        let stride = encoding_len(self.freqs);
        let start = i * stride;
        &self.enc[start..start + encoding_len(freqs.min(self.freqs))]
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
    /// Fold every pair into the part of the turn this keeps (for an anisotropic material
    /// with that symmetry; not with `isotropic`).
    pub fold: IncidentFold,
    /// Isotropic fits: fraction of `wi` drawn with `theta_i` uniform in angle (the rest
    /// uniform in solid angle).
    pub angle_fraction: f64,
    /// Consecutive pairs sharing one `wi` (1: every pair its own; see
    /// [`ExactConfig::group`]).
    pub group: usize,
}

impl TrainingData for MaterialPairs<'_> {
    fn pairs(&self) -> Vec<([f32; 3], [f32; 2])> {
        let both = self.domain.is_spherical() && self.material.is_transmissive();
        let cfg = ExactConfig {
            domain: self.domain,
            candidates: 64,
            seed: self.seed,
            group: self.group,
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
            .filter_map(|p| to_flow_pair(self.domain, &p.folded(self.fold), self.isotropic))
            .collect()
    }

    fn isotropic(&self) -> bool {
        self.isotropic
    }

    fn fold(&self) -> IncidentFold {
        self.fold
    }
}

/// `(wi, x1)` of a material pair in f32, turned into the incident frame of an isotropic
/// model first when `incident_frame` ([`Pair::in_incident_frame`], in f64); `None`
/// outside the domain. The disk point is the kernel's ([`Domain::point_of`]); the sphere
/// point is computed in f64 from the f64 direction and rounded once.
pub fn to_flow_pair(
    domain: Domain,
    p: &Pair,
    incident_frame: bool,
) -> Option<([f32; 3], [f32; 2])> {
    let p = if incident_frame {
        p.in_incident_frame()
    } else {
        *p
    };
    let f32s = |w: DVec3| [w.x as f32, w.y as f32, w.z as f32];
    let x1 = match domain {
        Domain::Disk => domain.point_of(f32s(p.wo).into(), f32s(p.wi).into())?,
        Domain::Sphere => [p.wo.theta() as f32, p.wo.phi() as f32],
        // The equatorial chart is the sphere's about the y axis (docs/math.md, (54)).
        Domain::Equatorial => {
            let (x, y, z) = (p.wo.x, p.wo.y, p.wo.z);
            [(x.hypot(z)).atan2(y) as f32, z.atan2(x) as f32]
        }
        // The half vector of the reflection, in f64 and rounded once (docs/math.md, §4.4).
        Domain::HalfVector => {
            let s = p.wi + p.wo;
            let len = s.length();
            if !(p.wo.z > 0.0 && p.wi.z > 0.0 && len > 0.0) {
                return None;
            }
            let h = s / len;
            [h.x as f32, h.y as f32]
        }
    };
    Some((f32s(p.wi), x1))
}
