//! The generated code against the kernel's definition: every `diffbsdf::spec` constant the
//! emitter prints is parsed back from the text of each language and precision and compared
//! with the kernel's value, so a constant restated (or mistyped) in `emit/` fails here.

use crate::desc::tests::blob;
use crate::{generate, Float, Language, Options};
use diffbsdf::spec::ERFC_POLY;
use diffbsdf::spec::{
    BASE_OUTPUTS, DET_REUSE_TOL, DET_SECANT_TOL, ENCODING_PER_FREQ, ENCODING_RAW, ERFINV_BRANCH_W,
    ERFINV_CENTRAL, ERFINV_CENTRAL_SHIFT, ERFINV_TAIL, ERFINV_TAIL_SHIFT, EXP_ARG_LIMIT_F16,
    EXP_ARG_MAX, EXP_ARG_MIN, GAUSSIAN_TAIL_MIN, LATENT_TABLE_CELLS, LATENT_TABLE_VALUE_CELLS,
    LINE_SEARCH_HALVINGS, LN_4PI, LN_INV_SQRT_2PI, LN_SCALE_MAX, LN_SCALE_MIN, NEWTON_MAX_ITERS,
    NEWTON_TOL, NEWTON_TOL_F16, NORMAL_INCIDENCE_RHO, STANDARD_WARP_K, UNIT_TOLERANCE,
    VELOCITY_OUTPUTS,
};
use diffbsdf::{Domain, ModelDef, TableGrid};

/// One generated output: what it is, and its text.
struct Output {
    label: String,
    def: ModelDef,
    half: bool,
    code: String,
}

/// Every language and precision, for an isotropic disk model, a sphere model, a
/// half-vector model in warped standard coordinates and the same with a latent table of
/// each grid.
fn outputs() -> Vec<Output> {
    let mut disk = ModelDef::paper_disk();
    disk.isotropic = true;
    let mut sphere = ModelDef::paper_sphere();
    sphere.isotropic = false;
    let mut warped = disk;
    warped.domain = Domain::HalfVector;
    warped.standardized = true;
    warped.standard_warp = true;
    let mut table = warped;
    table.latent_table = Some(TableGrid::Codes);
    let mut value_table = warped;
    value_table.latent_table = Some(TableGrid::Values);
    let mut axes_table = warped;
    axes_table.latent_table = Some(TableGrid::WarpedCodes);
    let mut blended_table = warped;
    blended_table.latent_table = Some(TableGrid::BlendedSlices);
    let mut out = Vec::new();
    for def in [
        disk,
        sphere,
        warped,
        table,
        value_table,
        axes_table,
        blended_table,
    ] {
        let bytes = blob(&def);
        for language in [Language::Glsl, Language::Wgsl, Language::C] {
            for float in [Float::F32, Float::F16] {
                if language == Language::C && float == Float::F16 {
                    continue;
                }
                let mut options = Options::new(language);
                options.float = float;
                let code = generate(&bytes, &options).expect("generate");
                out.push(Output {
                    label: format!(
                        "{:?}{} {language:?} {float:?}",
                        def.domain,
                        match def.latent_table {
                            Some(TableGrid::Codes) => " table",
                            Some(TableGrid::Values) => " value table",
                            Some(TableGrid::WarpedCodes) => " warped table",
                            Some(TableGrid::BlendedSlices) => " blended table",
                            None => "",
                        }
                    ),
                    def,
                    half: float == Float::F16,
                    code,
                });
            }
        }
    }
    out
}

/// The trimmed lines of generated function `name` (its header at column 0, up to the
/// closing `}` at column 0).
fn body<'a>(o: &'a Output, name: &str) -> Vec<&'a str> {
    let call = format!("_{name}(");
    let mut lines = o.code.lines();
    lines
        .by_ref()
        .find(|l| !l.starts_with(' ') && l.contains(&call) && l.ends_with('{'))
        .unwrap_or_else(|| panic!("{}: no function {name}", o.label));
    lines.take_while(|l| *l != "}").map(str::trim).collect()
}

/// The float literals of a line, in order (`1.0`, `-87.0f`, `2e-3`, `11.0hf`, `0.5h`).
fn lits(line: &str) -> Vec<f32> {
    line.split(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '+')))
        .filter(|t| {
            let digits = t.strip_prefix('-').unwrap_or(t);
            digits.starts_with(|c: char| c.is_ascii_digit()) && (t.contains('.') || t.contains('e'))
        })
        .map(|t| {
            let t = t.trim_end_matches("hf").trim_end_matches(['h', 'f']);
            t.parse::<f32>()
                .unwrap_or_else(|_| panic!("not a float literal: {t} in {line}"))
        })
        .collect()
}

/// The unsigned integer literals of a line (`32u`).
fn uints(line: &str) -> Vec<u32> {
    line.split(|c: char| !c.is_ascii_alphanumeric())
        .filter_map(|t| t.strip_suffix('u')?.parse().ok())
        .collect()
}

/// The one line of `lines` that starts with `start`.
fn line<'a>(o: &Output, lines: &[&'a str], start: &str) -> &'a str {
    let found: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with(start))
        .collect();
    assert_eq!(found.len(), 1, "{}: lines starting with {start:?}", o.label);
    found[0]
}

#[test]
fn activation_clamps_are_the_kernels() {
    for o in outputs() {
        let (lo, hi) = if o.half {
            (-EXP_ARG_LIMIT_F16, EXP_ARG_LIMIT_F16)
        } else {
            (EXP_ARG_MIN, EXP_ARG_MAX)
        };
        let b = body(&o, "sigmoid");
        let ret = line(&o, &b, "return");
        assert_eq!(lits(ret), [1.0, 1.0, lo, hi], "{}", o.label);
    }
}

#[test]
fn encoding_layout_is_the_kernels() {
    for o in outputs() {
        let b = body(&o, "encode");
        let at: Vec<&str> = b.iter().copied().filter(|l| l.ends_with("* k;")).collect();
        assert_eq!(at.len(), 1, "{}", o.label);
        let want = [ENCODING_RAW as u32, ENCODING_PER_FREQ as u32];
        assert_eq!(uints(at[0]), want, "{}", o.label);
    }
}

#[test]
fn gaussian_quantile_is_the_kernels() {
    let want: Vec<f32> = ERFINV_CENTRAL.iter().chain(&ERFINV_TAIL).copied().collect();
    for o in outputs() {
        let b = body(&o, "quantile");
        let coeffs: Vec<f32> = b
            .iter()
            .filter(|l| l.starts_with("p = "))
            .map(|l| lits(l)[0])
            .collect();
        assert_eq!(coeffs, want, "{}: erfinv coefficients", o.label);
        let branch = line(&o, &b, "if (w <");
        assert_eq!(lits(branch), [ERFINV_BRANCH_W], "{}", o.label);
        let central = line(&o, &b, "w = w -");
        assert_eq!(lits(central), [ERFINV_CENTRAL_SHIFT], "{}", o.label);
        let tail = b
            .iter()
            .find(|l| l.starts_with("w = ") && l.contains("sqrt"));
        let tail = tail.unwrap_or_else(|| panic!("{}: no tail shift", o.label));
        assert_eq!(lits(tail), [ERFINV_TAIL_SHIFT], "{}", o.label);
        let clamped = b.iter().rfind(|l| l.starts_with("q = "));
        let clamped = clamped.unwrap_or_else(|| panic!("{}: no clamp of q", o.label));
        assert_eq!(lits(clamped), [GAUSSIAN_TAIL_MIN, 0.5], "{}", o.label);
    }
}

#[test]
fn densities_and_scales_use_the_kernels_constants() {
    for o in outputs() {
        let b = body(&o, "base_ln_pdf");
        let ret = line(&o, &b, "return");
        assert!(lits(ret).contains(&LN_INV_SQRT_2PI), "{}", o.label);
        if o.def.domain == Domain::Sphere {
            let b = body(&o, "wrapped_cauchy_ln_pdf");
            let ret = line(&o, &b, "return");
            assert!(lits(ret).contains(&LN_4PI), "{}", o.label);
        }
        let b = body(&o, "condition");
        let clamps: Vec<Vec<f32>> = b
            .iter()
            .filter(|l| l.starts_with("r.p") && l.contains("outv"))
            .map(|l| lits(l))
            .collect();
        assert_eq!(clamps.len(), BASE_OUTPUTS, "{}", o.label);
        let scales: Vec<&Vec<f32>> = clamps.iter().filter(|c| !c.is_empty()).collect();
        assert_eq!(scales.len(), 2, "{}: two log-scales", o.label);
        for c in scales {
            assert_eq!(*c, [LN_SCALE_MIN, LN_SCALE_MAX], "{}", o.label);
        }
        let readout = format!("-> {BASE_OUTPUTS}:");
        assert!(b.iter().any(|l| l.contains(&readout)), "{}", o.label);
        let readout = format!("-> {VELOCITY_OUTPUTS}:");
        let v = body(&o, "velocity");
        assert!(v.iter().any(|l| l.contains(&readout)), "{}", o.label);
    }
}

#[test]
fn warp_scale_is_the_kernels() {
    let warped: Vec<Output> = outputs()
        .into_iter()
        .filter(|o| o.def.standard_warp)
        .collect();
    // The warped model and the four with a latent table, in five outputs each.
    assert_eq!(warped.len(), 25);
    for o in warped {
        // The first line of each is `a = |z| / K`, `s = y / K` or `a = |y| / K`.
        for name in ["warp_compress", "warp_expand", "warp_ln_expansion"] {
            let b = body(&o, name);
            assert_eq!(lits(b[0]), [STANDARD_WARP_K], "{}: {name}", o.label);
        }
    }
    for o in outputs().iter().filter(|o| !o.def.standard_warp) {
        assert!(!o.code.contains("warp_"), "{}", o.label);
    }
}

#[test]
fn input_checks_are_the_kernels() {
    for o in outputs() {
        let b = body(&o, "unit");
        let ok = line(&o, &b, "r.ok =");
        // `| |w|^2 - 1 | <= UNIT_TOLERANCE`, after the finiteness test (C compares with
        // FLT_MAX).
        assert!(
            lits(ok).ends_with(&[1.0, UNIT_TOLERANCE]),
            "{}: {ok}",
            o.label
        );
        if o.def.isotropic {
            let b = body(&o, "frame");
            let normal = line(&o, &b, "if (rho >");
            assert_eq!(lits(normal), [NORMAL_INCIDENCE_RHO], "{}", o.label);
        }
    }
}

#[test]
fn newton_constants_are_the_kernels() {
    for o in outputs() {
        let tol = if o.half { NEWTON_TOL_F16 } else { NEWTON_TOL };
        let b = body(&o, "newton");
        // One loop over residual evaluations: the start, NEWTON_MAX_ITERS iterations of at
        // most LINE_SEARCH_HALVINGS + 1 trials each, and the converged point.
        let evaluations = b
            .iter()
            .find(|l| l.starts_with("for (") && l.contains("k <"));
        let evaluations = evaluations.unwrap_or_else(|| panic!("{}: no Newton loop", o.label));
        assert_eq!(
            uints(evaluations),
            [0, 2 + NEWTON_MAX_ITERS * (LINE_SEARCH_HALVINGS + 1)],
            "{}",
            o.label
        );
        let iters = line(&o, &b, "if (it ==");
        assert_eq!(uints(iters), [NEWTON_MAX_ITERS], "{}", o.label);
        let last = b.iter().find(|l| l.contains("< norm || ls =="));
        let last = last.unwrap_or_else(|| panic!("{}: no last-halving test", o.label));
        assert_eq!(uints(last), [LINE_SEARCH_HALVINGS], "{}", o.label);
        let converged = line(&o, &b, "if (size <=");
        assert_eq!(lits(converged), [tol], "{}", o.label);
        let stalled = line(&o, &b, "if (lambda * size <=");
        assert_eq!(lits(stalled), [tol, 0.0], "{}", o.label);
        let reuse = line(&o, &b, "if (size >");
        assert_eq!(lits(reuse), [DET_REUSE_TOL], "{}", o.label);
        // The secant bound's line declares `det_flat` (its type is the dialect's).
        let flat: Vec<&str> = b
            .iter()
            .copied()
            .filter(|l| l.contains("(size / pstep)"))
            .collect();
        assert_eq!(flat.len(), 1, "{}: the secant bound", o.label);
        assert_eq!(
            lits(flat[0]),
            [0.0, 0.0, 0.0, DET_SECANT_TOL],
            "{}",
            o.label
        );
    }
}

#[test]
fn latent_table_layout_and_cdf_are_the_kernels() {
    let mut seen = 0;
    for o in outputs().iter() {
        let Some(grid) = o.def.latent_table else {
            continue;
        };
        seen += 1;
        let want_cells = match grid {
            TableGrid::Codes | TableGrid::WarpedCodes | TableGrid::BlendedSlices => {
                LATENT_TABLE_CELLS
            }
            TableGrid::Values => LATENT_TABLE_VALUE_CELLS,
        };
        let b = body(o, "normal_cdf");
        let coeffs: Vec<f32> = b
            .iter()
            .filter(|l| l.starts_with("p = "))
            .map(|l| lits(l)[0])
            .collect();
        assert_eq!(coeffs, ERFC_POLY, "{}: erfc coefficients", o.label);
        let b = body(o, "table_node");
        let at = b.iter().copied().find(|l| l.contains("cond.tk *"));
        let at = at.unwrap_or_else(|| panic!("{}: no node offset", o.label));
        let offset = (o.def.param_count() - o.def.table_len()) as u32;
        assert_eq!(
            uints(at),
            [
                offset,
                ((want_cells + 1) * (want_cells + 1)) as u32,
                want_cells as u32 + 1
            ],
            "{}",
            o.label
        );
        let b = body(o, "condition");
        let slices = line(o, &b, "if (r.tk >");
        assert_eq!(uints(slices), [grid.slices() as u32 - 2], "{}", o.label);
        let b = body(o, "table_ln_density");
        let mut cells = 0;
        for l in b.iter().filter(|l| l.starts_with("if (")) {
            let want = if l.contains("==") {
                // The trapezoid weights' ends.
                vec![0, want_cells as u32]
            } else {
                cells += 1;
                vec![want_cells as u32 - 1]
            };
            assert_eq!(uints(l), want, "{}: {l}", o.label);
        }
        assert_eq!(cells, 2, "{}: the cells of both coordinates", o.label);
        // The axis warps' nodes follow the slices' (docs/math.md, (81)).
        if grid.is_warped() {
            let b = body(o, "table_axis");
            let at = b.iter().copied().find(|l| l.contains("ax *"));
            let at = at.unwrap_or_else(|| panic!("{}: no axis offset", o.label));
            let slices = (grid.slices() * (want_cells + 1) * (want_cells + 1)) as u32;
            assert_eq!(
                uints(at),
                [offset + slices, want_cells as u32 + 1],
                "{}",
                o.label
            );
        }
    }
    assert_eq!(seen, 20, "the table models in every language and precision");
}
