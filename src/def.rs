//! The model definition: one value that fully describes a model's architecture. The blob
//! stores it, the kernel checks it against its compiled shape, and codegen and the trainer
//! read it.

pub use crate::base::table::TableGrid;
use crate::spec::{BASE_OUTPUTS, ENCODING_PER_FREQ, ENCODING_RAW, VELOCITY_OUTPUTS};

/// Where the flow lives, and so how a point `x` of the flow maps to a direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Domain {
    /// Projected unit disk `x = (wo.x, wo.y)`, upper hemisphere only (BRDFs).
    Disk,
    /// Spherical coordinates `x = (theta, phi)` over the whole sphere (full BSDFs).
    Sphere,
    /// Spherical coordinates about the tangent `y` axis: `wo = (sin t cos p, cos t,
    /// sin t sin p)`, so the normal and the plane of incidence (of an isotropic model) lie
    /// on the chart's equator, away from its poles (`docs/math.md`, §4.3).
    Equatorial,
    /// The half vector `h = (wi + wo) / |wi + wo|` on the projected unit disk, `x = (h.x,
    /// h.y)`: reflection only, upper hemisphere (measured and glossy BRDFs; `docs/math.md`,
    /// §4.4). Features, base distribution and steps are the disk's.
    HalfVector,
}

impl Domain {
    /// Number of flow-state features the velocity net sees: `(x, y)` on the disk,
    /// `(theta, sin phi, cos phi)` on the sphere.
    #[must_use]
    pub const fn feature_count(self) -> usize {
        match self {
            Domain::Disk | Domain::HalfVector => 2,
            Domain::Sphere | Domain::Equatorial => 3,
        }
    }

    /// Whether the flow lives in spherical coordinates `(theta, phi)` over the whole
    /// sphere (the sphere and the equatorial chart): same features, base distribution,
    /// measure and steps; only the axis of the chart differs.
    #[must_use]
    pub const fn is_spherical(self) -> bool {
        matches!(self, Domain::Sphere | Domain::Equatorial)
    }

    /// The domain's name in reports, file names and the Python and CLI interfaces.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Domain::Disk => "disk",
            Domain::Sphere => "sphere",
            Domain::Equatorial => "equatorial",
            Domain::HalfVector => "half-vector",
        }
    }

    /// The domain's code in the blob header, also `diffbsdf_info.domain` in the C ABI.
    #[must_use]
    pub const fn code(self) -> u8 {
        match self {
            Domain::Disk => 0,
            Domain::Sphere => 1,
            Domain::Equatorial => 2,
            Domain::HalfVector => 3,
        }
    }

    pub(crate) const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Domain::Disk),
            1 => Some(Domain::Sphere),
            2 => Some(Domain::Equatorial),
            3 => Some(Domain::HalfVector),
            _ => None,
        }
    }
}

/// The incident directions `wi` a model is defined for: it returns no sample and PDF 0
/// for any other `wi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IncidentRange {
    /// `wi.z >= 0` only: reflection-only materials (every disk model; a BRDF fitted on the
    /// sphere). A renderer flips `wi` and `wo` of a two-sided BRDF before calling.
    UpperHemisphere,
    /// Every `wi`: transmissive materials on the sphere.
    WholeSphere,
}

/// A symmetry of an anisotropic material in the incident azimuth, which a model uses to
/// learn only part of the turn: the nets see `wi` folded into it and a sample is unfolded
/// by the same signs ([`crate::internals::frame::IncidentFrame::folding`]). Mirrors and
/// a half turn keep solid angle, so every density is unchanged and the reported PDF
/// stays exact. (An isotropic model's rotation, [`ModelDef::isotropic`], subsumes both.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IncidentFold {
    /// No fold: `wi` at every azimuth.
    None,
    /// Unchanged by a half turn about the normal (blob flag bit 8): a `wi` with `y > 0` is
    /// turned by `pi`, so the nets see `phi_i` in `[-pi, 0]`.
    HalfTurn,
    /// Unchanged by mirroring `x` and by mirroring `y` (an anisotropic lobe aligned with
    /// the axes; blob flag bit 9): `wi.x` and `wi.y` are each made negative or zero, so
    /// the nets see `phi_i` in `[-pi, -pi/2]`.
    Quarter,
}

impl IncidentFold {
    /// The fold's code in the C ABI's `diffbsdf_info.incident_fold`: 0 none, 1 a half
    /// turn, 2 a quarter.
    #[must_use]
    pub const fn code(self) -> u8 {
        match self {
            IncidentFold::None => 0,
            IncidentFold::HalfTurn => 1,
            IncidentFold::Quarter => 2,
        }
    }

    /// The signs `(sx, sy)` that fold a `wi` with tangent part `(x, y)` into the kept part
    /// of the turn (docs/math.md, (83)): `-1` where the coordinate is `>= 0` (so `-0`
    /// counts as `>= 0`), for both from `y` on a half turn, each from its own on a
    /// quarter; `(1, 1)` without a fold. The same signs fold a `wo` with it and unfold a
    /// sampled one (each is its own inverse).
    #[inline]
    #[must_use]
    pub fn signs(self, x: f32, y: f32) -> (f32, f32) {
        let negate = |v: f32| if v >= 0.0 { -1.0 } else { 1.0 };
        match self {
            IncidentFold::None => (1.0, 1.0),
            IncidentFold::HalfTurn => (negate(y), negate(y)),
            IncidentFold::Quarter => (negate(x), negate(y)),
        }
    }

    /// The kept azimuths `[start, start + span]` of `wi` (what the nets see): the whole
    /// turn `[0, 2 pi]`, `[-pi, 0]` or `[-pi, -pi/2]`.
    #[must_use]
    pub fn kept_azimuths(self) -> (f32, f32) {
        use core::f32::consts::{FRAC_PI_2, PI, TAU};
        match self {
            IncidentFold::None => (0.0, TAU),
            IncidentFold::HalfTurn => (-PI, PI),
            IncidentFold::Quarter => (-PI, FRAC_PI_2),
        }
    }
}

/// How weights are stored in the blob. The kernel evaluates in f32 either way; f16 blobs
/// are half the size, and generated shaders can evaluate them in f16.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Precision {
    /// 4-byte IEEE single precision.
    F32,
    /// 2-byte IEEE half precision.
    F16,
}

impl Precision {
    /// Bytes per stored weight.
    #[must_use]
    pub const fn bytes(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F16 => 2,
        }
    }

    pub(crate) const fn code(self) -> u8 {
        match self {
            Precision::F32 => 0,
            Precision::F16 => 1,
        }
    }

    pub(crate) const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Precision::F32),
            1 => Some(Precision::F16),
            _ => None,
        }
    }
}

/// Hidden-layer activation. Only SiLU exists today; the blob reserves the byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Activation {
    /// `silu(z) = z * sigmoid(z)`.
    Silu,
}

impl Activation {
    pub(crate) const fn code(self) -> u8 {
        0
    }

    pub(crate) const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Activation::Silu),
            _ => None,
        }
    }
}

/// Shape of one MLP: the frequencies of its `wi` encoding, its hidden width and its number
/// of hidden layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NetShape {
    /// NeRF frequencies of the `wi` encoding (`2^k * pi` for `k < freqs`).
    pub freqs: u8,
    /// Neurons per hidden layer.
    pub width: u16,
    /// Hidden layers (at least 1).
    pub hidden_layers: u8,
}

impl NetShape {
    /// Length of the `wi` encoding: the raw `wi` and a sine and cosine per frequency and axis.
    #[must_use]
    pub const fn encoding_len(self) -> usize {
        encoding_len(self.freqs)
    }
}

/// Length of the NeRF encoding of `wi` with `freqs` frequencies: `3 + 6 * freqs`.
#[must_use]
pub const fn encoding_len(freqs: u8) -> usize {
    ENCODING_RAW + ENCODING_PER_FREQ * freqs as usize
}

/// One of a model's two networks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Net {
    /// `wi` encoding (`base.freqs`) -> the four parameters of `p0(x0 | wi)`.
    Base,
    /// `[flow features (Domain::feature_count), t, wi encoding (velocity.freqs)]` -> `v`.
    Velocity,
}

impl Net {
    /// Both nets, in blob order.
    pub const ALL: [Net; 2] = [Net::Base, Net::Velocity];
}

/// One fully connected layer `z = W x + b`; the blob stores `W` row by row (one output's
/// weights over every input), then `b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Layer {
    /// Inputs (columns of `W`).
    pub inputs: usize,
    /// Outputs (rows of `W`, entries of `b`).
    pub outputs: usize,
    /// Whether the model's activation follows (every layer but the readout).
    pub activated: bool,
}

impl Layer {
    /// Weights and biases of the layer: `outputs * (inputs + 1)`.
    #[must_use]
    pub const fn param_count(&self) -> usize {
        self.outputs * (self.inputs + 1)
    }
}

/// Longest model name stored in a blob, in bytes.
pub const NAME_CAPACITY: usize = 32;

/// A short UTF-8 label stored in the blob (codegen names things after it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ModelName {
    bytes: [u8; NAME_CAPACITY],
    len: u8,
}

impl ModelName {
    /// The empty name.
    pub const EMPTY: ModelName = ModelName {
        bytes: [0; NAME_CAPACITY],
        len: 0,
    };

    /// A name from a string; `None` if it is longer than [`NAME_CAPACITY`] bytes.
    #[must_use]
    pub fn new(name: &str) -> Option<Self> {
        Self::from_bytes(name.as_bytes())
    }

    /// A name from bytes; `None` if too long or not UTF-8.
    #[must_use]
    pub fn from_bytes(raw: &[u8]) -> Option<Self> {
        if raw.len() > NAME_CAPACITY || core::str::from_utf8(raw).is_err() {
            return None;
        }
        let mut bytes = [0; NAME_CAPACITY];
        bytes[..raw.len()].copy_from_slice(raw);
        Some(ModelName {
            bytes,
            len: raw.len() as u8,
        })
    }

    /// The name as text.
    #[must_use]
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(self.as_bytes()).unwrap_or("")
    }

    /// The name's bytes.
    #[must_use]
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..self.len as usize).unwrap_or(&[])
    }
}

/// Everything that describes a model except its weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ModelDef {
    /// Where the flow lives.
    pub domain: Domain,
    /// How the blob stores the weights.
    pub precision: Precision,
    /// The hidden layers' activation.
    pub activation: Activation,
    /// The base net: `wi` encoding -> parameters of `p0(x0 | wi)`.
    pub base: NetShape,
    /// The velocity net: `(x features, t, wi encoding)` -> `v`.
    pub velocity: NetShape,
    /// Euler steps used when the caller does not choose.
    pub default_steps: u16,
    /// The material is unchanged by rotations about the normal: the nets see `wi` turned
    /// into the xz-plane and samples are turned back ([`crate::internals::frame::IncidentFrame`]).
    pub isotropic: bool,
    /// An anisotropic material's symmetry in the incident azimuth (blob flag bits 8, 9):
    /// the nets see `wi` folded into part of the turn. A header error with
    /// [`ModelDef::isotropic`].
    pub fold: IncidentFold,
    /// Which `wi` the model was trained for and answers (blob flag bit 1 on the sphere;
    /// always the upper hemisphere on the disk). A sphere blob written before the flag
    /// existed has no bit and means [`IncidentRange::WholeSphere`].
    pub incident: IncidentRange,
    /// The flow runs in the base distribution's standard coordinates
    /// `z = (x - mu(wi)) / sigma(wi)` and its end point is mapped to the chart by `x = mu +
    /// sigma z` (docs/math.md, §6.3; blob flag bit 2). Disk and half-vector chart only.
    pub standardized: bool,
    /// With [`ModelDef::standardized`]: the flow runs in the compressed standard
    /// coordinates `y = K asinh(z / K)` ([`crate::spec::STANDARD_WARP_K`]; docs/math.md,
    /// §6.4; blob flag bit 3). A header error without `standardized`.
    pub standard_warp: bool,
    /// With [`ModelDef::standardized`]: `u` is drawn through the latent table, a bilinear
    /// density on `[0, 1]^2` per incidence slice, fitted to where the flow alone falls short
    /// (docs/math.md, §6.5; blob flag bit 4; its nodes follow the nets' weights), on the
    /// given grid ([`TableGrid::Codes`]: flag bit 5). A header error without
    /// `standardized`.
    pub latent_table: Option<TableGrid>,
    /// A short label (codegen names things after it).
    pub name: ModelName,
}

impl ModelDef {
    /// The paper's disk model: base 1x16 (3 frequencies), velocity 3x32 (5 frequencies),
    /// 4 Euler steps.
    #[must_use]
    pub const fn paper_disk() -> Self {
        ModelDef {
            domain: Domain::Disk,
            precision: Precision::F32,
            activation: Activation::Silu,
            base: NetShape {
                freqs: 3,
                width: 16,
                hidden_layers: 1,
            },
            velocity: NetShape {
                freqs: 5,
                width: 32,
                hidden_layers: 3,
            },
            default_steps: 4,
            isotropic: false,
            fold: IncidentFold::None,
            incident: IncidentRange::UpperHemisphere,
            standardized: false,
            standard_warp: false,
            latent_table: None,
            name: ModelName::EMPTY,
        }
    }

    /// The paper's sphere model: as the disk model but velocity 4x32, 8 Euler steps and
    /// every `wi` (a full BSDF).
    #[must_use]
    pub const fn paper_sphere() -> Self {
        let mut def = Self::paper_disk();
        def.domain = Domain::Sphere;
        def.incident = IncidentRange::WholeSphere;
        def.velocity.hidden_layers = 4;
        def.default_steps = 8;
        def
    }

    /// Whether the model answers for incident direction `wi` (any length; checked on
    /// its `z`): the disk only ever above the surface, the sphere as declared.
    #[must_use]
    pub fn accepts_incident_z(&self, wi_z: f32) -> bool {
        match (self.domain, self.incident) {
            (Domain::Sphere | Domain::Equatorial, IncidentRange::WholeSphere) => true,
            _ => wi_z >= 0.0,
        }
    }

    /// Inputs of the velocity net's first layer: features, `t`, `wi` encoding.
    #[must_use]
    pub const fn velocity_inputs(&self) -> usize {
        self.domain.feature_count() + 1 + self.velocity.encoding_len()
    }

    /// The shape of `net`.
    #[must_use]
    pub const fn net_shape(&self, net: Net) -> NetShape {
        match net {
            Net::Base => self.base,
            Net::Velocity => self.velocity,
        }
    }

    /// Inputs of `net`'s first layer.
    #[must_use]
    pub const fn net_inputs(&self, net: Net) -> usize {
        match net {
            Net::Base => self.base.encoding_len(),
            Net::Velocity => self.velocity_inputs(),
        }
    }

    /// Outputs of `net`'s readout.
    #[must_use]
    pub const fn net_outputs(&self, net: Net) -> usize {
        match net {
            Net::Base => BASE_OUTPUTS,
            Net::Velocity => VELOCITY_OUTPUTS,
        }
    }

    /// Layers of `net`: its hidden layers and the readout.
    #[must_use]
    pub const fn layer_count(&self, net: Net) -> usize {
        self.net_shape(net).hidden_layers as usize + 1
    }

    /// Layer `index` of `net` (0 is the first hidden layer, `layer_count - 1` the
    /// readout); `None` past the readout.
    #[must_use]
    pub const fn layer(&self, net: Net, index: usize) -> Option<Layer> {
        let count = self.layer_count(net);
        if index >= count {
            return None;
        }
        let width = self.net_shape(net).width as usize;
        let inputs = if index == 0 {
            self.net_inputs(net)
        } else {
            width
        };
        let readout = index + 1 == count;
        Some(Layer {
            inputs,
            outputs: if readout {
                self.net_outputs(net)
            } else {
                width
            },
            activated: !readout,
        })
    }

    /// Weights and biases of `net`, summed over its layers.
    #[must_use]
    pub const fn net_param_count(&self, net: Net) -> usize {
        let mut total = 0;
        let mut index = 0;
        while let Some(layer) = self.layer(net, index) {
            total += layer.param_count();
            index += 1;
        }
        total
    }

    /// Number of weights and biases, in the order the blob stores them (base net first).
    #[must_use]
    pub const fn param_count(&self) -> usize {
        self.net_param_count(Net::Base) + self.net_param_count(Net::Velocity) + self.table_len()
    }

    /// Node values of the latent table the blob stores after the nets' weights (its grid's
    /// [`TableGrid::node_count`]; 0 without a table).
    #[must_use]
    pub const fn table_len(&self) -> usize {
        match self.latent_table {
            Some(grid) => grid.node_count(),
            None => 0,
        }
    }
}
