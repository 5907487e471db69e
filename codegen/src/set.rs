//! Code for a set of materials: only the code paths the set uses.
//!
//! With baked weights every model gets its own functions (prefix `PREFIX_<model name>`).
//! With weights in a buffer the models are grouped by architecture (domain, activation
//! and net shapes): each group is emitted once, reading its own buffer (bindings
//! `binding`, `binding + 1`, ... in group order), and every material gets two constants,
//! `GROUP_<NAME>_BASE` (its offset in floats in its group's buffer) and `GROUP_<NAME>_STEPS`
//! (its default Euler steps, to pass as `steps`: the group's `DEFAULT_STEPS` is its first
//! model's). A disk-only set therefore carries no sphere code, and an entry point nobody
//! asked for is not emitted at all.

use crate::code::Namer;
use crate::{generate_from, Error, Language, ModelDesc, Options, Weights};
use diffbsdf::ModelDef;

/// One material of a set.
#[derive(Clone, Debug)]
pub struct Material {
    /// Its name in the generated constants (made a legal identifier).
    pub name: String,
    /// The parsed blob.
    pub model: ModelDesc,
}

/// The weights of one architecture group in buffer mode.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupBuffer {
    /// Name prefix of the group's functions.
    pub prefix: String,
    /// Binding of its buffer (set as in the options).
    pub binding: u32,
    /// Every material's parameters back to back (f32, blob order).
    pub params: Vec<f32>,
}

/// Generated code for a set, and the buffers it reads (empty with baked weights).
#[derive(Clone, Debug, PartialEq)]
pub struct SetCode {
    /// The code.
    pub code: String,
    /// One buffer per architecture group.
    pub buffers: Vec<GroupBuffer>,
}

/// Whether code generated for `a` also serves `b` with `b`'s weights in buffer mode
/// (everything the generated code depends on besides the weights and the default steps).
pub fn same_architecture(a: &ModelDef, b: &ModelDef) -> bool {
    architecture(a) == architecture(b)
}

/// The part of a definition the generated code depends on besides the weights.
fn architecture(d: &ModelDef) -> impl PartialEq {
    (
        d.domain,
        d.activation,
        d.base,
        d.velocity,
        d.isotropic,
        d.fold,
        d.accepts_incident_z(-1.0),
        d.standardized,
        d.standard_warp,
        d.latent_table,
    )
}

fn namer(language: Language) -> Namer {
    match language {
        Language::Glsl => Namer::new(crate::glsl::keywords::RESERVED),
        Language::Wgsl => Namer::new(crate::wgsl::keywords::RESERVED),
        Language::C => Namer::new(crate::c::keywords::RESERVED),
    }
}

/// `name = value` as an unsigned constant in `language`.
fn constant(language: Language, name: &str, value: usize) -> String {
    match language {
        Language::Glsl => format!("const uint {name} = {value}u;"),
        Language::Wgsl => format!("const {name}: u32 = {value}u;"),
        Language::C => format!("#define {name} {value}u"),
    }
}

/// Generates the code for `materials` with `options` (its prefix, default `diffbsdf`,
/// starts every group's or model's prefix).
pub fn generate_set(materials: &[Material], options: &Options) -> Result<SetCode, Error> {
    let n = namer(options.language);
    let root = options.prefix.clone().unwrap_or_else(|| "diffbsdf".into());
    let mut names: Vec<String> = Vec::with_capacity(materials.len());
    for m in materials {
        let name = n.ident(&m.name);
        if names.contains(&name) {
            return Err(Error::Unsupported(
                "two materials of a set have the same name",
            ));
        }
        names.push(name);
    }
    let mut parts = Vec::new();
    let mut buffers = Vec::new();
    match options.weights {
        Weights::Baked => {
            for (m, name) in materials.iter().zip(&names) {
                let mut o = options.clone();
                o.prefix = Some(format!("{root}_{name}"));
                parts.push(generate_from(&m.model, &o)?);
            }
        }
        Weights::Buffer { set, binding } => {
            let mut groups: Vec<Vec<usize>> = Vec::new();
            for (k, m) in materials.iter().enumerate() {
                let a = architecture(&m.model.def);
                match groups
                    .iter_mut()
                    .find(|g| architecture(&materials[g[0]].model.def) == a)
                {
                    Some(g) => g.push(k),
                    None => groups.push(vec![k]),
                }
            }
            for (gi, g) in groups.iter().enumerate() {
                let first = &materials[g[0]].model;
                let domain = first.def.domain.name().replace('-', "_");
                let prefix = n.ident(&format!("{root}_{domain}{gi}"));
                let mut o = options.clone();
                o.prefix = Some(prefix.clone());
                o.weights = Weights::Buffer {
                    set,
                    binding: binding + gi as u32,
                };
                let mut code = generate_from(first, &o)?;
                let mut params = Vec::new();
                code += "\n";
                // `//` comments are valid in all three languages (C99 included).
                code += &format!(
                    "// Materials in {prefix}'s buffer: offset in floats, default steps.\n"
                );
                for &k in g {
                    let up = |s: &str| format!("{}_{}", prefix, names[k]).to_uppercase() + s;
                    code += &constant(options.language, &up("_BASE"), params.len());
                    code += "\n";
                    let steps = materials[k].model.def.default_steps as usize;
                    code += &constant(options.language, &up("_STEPS"), steps);
                    code += "\n";
                    params.extend_from_slice(&materials[k].model.params);
                }
                parts.push(code);
                buffers.push(GroupBuffer {
                    prefix,
                    binding: binding + gi as u32,
                    params,
                });
            }
        }
    }
    Ok(SetCode {
        code: parts.join("\n"),
        buffers,
    })
}
