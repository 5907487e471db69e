//! RGL measured files: all six real files load; truncated and corrupted copies are
//! rejected with an error (never a panic); the tabular sampler passes the chi-square test
//! against its own PDF and its PDF integrates to the sampled-mass fraction, on the six
//! files and on anisotropic copies of one (the reader's path for files measured at more
//! than two incident azimuths, which none of the six is: over the whole turn, half of it
//! and a quarter, the last two folded); a spectral copy (`spectra` over `wavelengths`, the
//! database's `_spec` files) has the RGB file's luminance.

mod common;
mod tensor_copy;

use common::{chi2_of_samples, dir_deg, rng, Domain, ALPHA};
use diffbsdf_materials::rgl::{RglError, RglMaterial};
use diffbsdf_materials::IncidentFold;
use diffbsdf_materials::{DVec3, Material};
use rand::Rng;
use std::f64::consts::PI;
use tensor_copy::{rewrite, Out, Rewrite};

/// The measured files: `shared/data/rgl/` beside the repository.
fn data_dir() -> String {
    let beside = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/rgl");
    assert!(
        std::path::Path::new(beside).is_dir(),
        "RGL test data missing: expected {beside} (the shared/ folder beside the repository)"
    );
    beside.to_string()
}
const FILES: [&str; 6] = [
    "aurora_white_rgb.bsdf",
    "cc_nothern_aurora_rgb.bsdf",
    "chm_orange_rgb.bsdf",
    "ilm_solo_m_68_rgb.bsdf",
    "irid_flake_paint1_rgb.bsdf",
    "vch_golden_yellow_rgb.bsdf",
];

fn path(f: &str) -> String {
    format!("{}/{f}", data_dir())
}

#[test]
fn reads_all_six_files() {
    for f in FILES {
        let m = RglMaterial::open(&path(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(!m.description.is_empty(), "{f}");
        let wi = dir_deg(30.0, 0.0);
        let v = m.eval(wi, dir_deg(30.0, std::f64::consts::PI));
        assert!(v.is_finite() && v.max_channel() > 0.0, "{f}: {v:?}");
    }
}

#[test]
fn rejects_truncated_and_corrupted_copies() {
    let bytes = std::fs::read(path(FILES[0])).unwrap();
    for cut in [
        0,
        5,
        12,
        17,
        30,
        100,
        415,
        600,
        3000,
        bytes.len() / 2,
        bytes.len() - 1,
    ] {
        assert!(
            RglMaterial::from_bytes(&bytes[..cut]).is_err(),
            "cut at {cut}"
        );
    }
    let corrupt = |at: usize, v: u8| {
        let mut b = bytes.clone();
        b[at] = v;
        RglMaterial::from_bytes(&b)
    };
    assert_eq!(corrupt(0, b'x').unwrap_err(), RglError::BadMagic);
    assert!(matches!(
        corrupt(12, 2).unwrap_err(),
        RglError::UnsupportedVersion { .. }
    ));
    // Field count far larger than the header: runs off the end.
    assert_eq!(corrupt(17, 0x7f).unwrap_err(), RglError::Truncated);
    // First field: u16 name length at 18, name "version" (7 bytes), u16 ndim at 27, dtype at 29.
    assert_eq!(corrupt(29, 0).unwrap_err(), RglError::BadDtype(0));
    assert_eq!(corrupt(29, 99).unwrap_err(), RglError::BadDtype(99));
    // Its offset's top byte (offset at 30..38): far past the end.
    assert!(matches!(
        corrupt(37, 0x40).unwrap_err(),
        RglError::Truncated | RglError::Overflow
    ));
    // NaN inside the theta_i table (f32 at offset 488 in this file).
    let mut b = bytes.clone();
    b[488..492].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(
        RglMaterial::from_bytes(&b).unwrap_err(),
        RglError::NonFinite("theta_i")
    );
    // A sampled table with no mass.
    let mut b = bytes.clone();
    for x in b[526_856..526_856 + 4 * 1024].iter_mut() {
        *x = 0;
    }
    assert_eq!(
        RglMaterial::from_bytes(&b).unwrap_err(),
        RglError::NotNormalizable("luminance")
    );
    // Random byte flips anywhere never panic.
    let mut r = rng(3);
    for _ in 0..300 {
        let mut b = bytes.clone();
        let i = r.gen_range(0..600);
        b[i] = r.gen();
        let _ = RglMaterial::from_bytes(&b);
    }
    assert!(matches!(
        RglMaterial::open("/nonexistent.bsdf"),
        Err(RglError::Io(_))
    ));
}

/// A copy of the file `bytes` measured at `p` incident azimuths evenly spread over [-pi,
/// pi], each with the file's one set of tables: more than two azimuths make it anisotropic
/// (RGL-FORMAT.md), so its half-vector azimuths are read as they are, not relative to
/// `phi_i`; at `phi_i = 0` the two readings agree.
fn anisotropic_copy(bytes: &[u8], p: usize) -> Vec<u8> {
    azimuth_copy(bytes, p, -PI, PI)
}

/// [`anisotropic_copy`] with its `p` azimuths over `[from, to]` only: over half the turn
/// or a quarter of it, a reader folds every direction into that range.
fn azimuth_copy(bytes: &[u8], p: usize, from: f64, to: f64) -> Vec<u8> {
    rewrite(bytes, |f| match f.name.as_str() {
        "phi_i" => Rewrite::Replace(Out {
            name: f.name.clone(),
            dtype: 10,
            shape: vec![p],
            data: (0..p)
                .map(|k| (from + (to - from) * k as f64 / (p - 1) as f64) as f32)
                .flat_map(f32::to_le_bytes)
                .collect(),
        }),
        "vndf" | "luminance" | "rgb" => Rewrite::Gather(
            std::iter::once(vec![0; p])
                .chain(f.shape.iter().skip(1).map(|&n| (0..n).collect()))
                .collect(),
        ),
        _ => Rewrite::Keep,
    })
}

#[test]
fn anisotropic_copy_reads_absolute_azimuths() {
    let bytes = std::fs::read(path("vch_golden_yellow_rgb.bsdf")).unwrap();
    let iso = RglMaterial::from_bytes(&bytes).unwrap();
    let aniso = RglMaterial::from_bytes(&anisotropic_copy(&bytes, 5)).unwrap();
    assert!(iso.is_isotropic() && !aniso.is_isotropic());
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    let mut rotated = 0;
    // At phi_i = 0 the tables are read at the same azimuths.
    for (wi, wo) in pairs(0.0) {
        let (a, b) = (iso.eval_cos(wi, wo), aniso.eval_cos(wi, wo));
        assert!(
            close(a.max_channel(), b.max_channel()),
            "{wi:?} {wo:?}: {a:?} {b:?}"
        );
        assert!(close(iso.pdf(wi, wo), aniso.pdf(wi, wo)), "{wi:?} {wo:?}");
        // Turning `wi` and `wo` together about the normal keeps the isotropic file's
        // value and moves the copy's (its lobe stays at its absolute azimuths).
        let turn = |w: DVec3| DVec3::new(-w.y, w.x, w.z);
        let (wi_t, wo_t) = (turn(wi), turn(wo));
        let iso_t = iso.eval_cos(wi_t, wo_t).max_channel();
        assert!(
            (iso_t - a.max_channel()).abs() <= 1e-9 * iso_t.max(1e-12),
            "{wi:?}"
        );
        let aniso_t = aniso.eval_cos(wi_t, wo_t).max_channel();
        rotated += usize::from((aniso_t - a.max_channel()).abs() > 1e-3 * aniso_t.max(1e-12));
    }
    assert!(
        rotated >= 8,
        "only {rotated} of 20 turned pairs differ on the anisotropic copy"
    );
}

/// Pairs of directions the azimuth tests evaluate: `wi` at `phi_i` with `theta_i` in
/// 20-85 deg, `wo` spread over the hemisphere.
fn pairs(phi_i: f64) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for theta_i in [20.0, 45.0, 70.0, 85.0] {
        for (theta_o, phi_o) in [
            (10.0, 3.0),
            (30.0, PI),
            (50.0, 2.0),
            (60.0, 0.5),
            (75.0, 4.0),
        ] {
            out.push((dir_deg(theta_i, phi_i), dir_deg(theta_o, phi_o)));
        }
    }
    out
}

#[test]
fn copies_over_half_or_a_quarter_turn_fold_azimuths() {
    let bytes = std::fs::read(path("vch_golden_yellow_rgb.bsdf")).unwrap();
    let full = RglMaterial::from_bytes(&anisotropic_copy(&bytes, 5)).unwrap();
    let half = RglMaterial::from_bytes(&azimuth_copy(&bytes, 4, -PI, 0.0)).unwrap();
    let quarter = RglMaterial::from_bytes(&azimuth_copy(&bytes, 3, -PI, -PI / 2.0)).unwrap();
    assert_eq!(full.azimuth_fold(), IncidentFold::None);
    assert_eq!(half.azimuth_fold(), IncidentFold::HalfTurn);
    assert_eq!(quarter.azimuth_fold(), IncidentFold::Quarter);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    // Inside its stored range a folded copy reads the tables as the whole-turn copy does.
    for (m, phi_i) in [(&half, -1.0), (&quarter, -2.0)] {
        for (wi, wo) in pairs(phi_i) {
            let (a, b) = (full.eval_cos(wi, wo), m.eval_cos(wi, wo));
            assert!(
                close(a.max_channel(), b.max_channel()),
                "{phi_i}: {a:?} {b:?}"
            );
            assert!(close(full.pdf(wi, wo), m.pdf(wi, wo)), "{phi_i}");
        }
    }
    // Outside it, the material is its symmetric image: a half turn about the normal for
    // the half-turn copy, a mirror about either axis for the quarter one (`wi` in the
    // first quadrant, where an unfolded reading would clamp to the stored azimuths).
    let turn = |w: DVec3| DVec3::new(-w.x, -w.y, w.z);
    let mirror_x = |w: DVec3| DVec3::new(-w.x, w.y, w.z);
    let mirror_y = |w: DVec3| DVec3::new(w.x, -w.y, w.z);
    let images: [(&RglMaterial, &dyn Fn(DVec3) -> DVec3); 3] =
        [(&half, &turn), (&quarter, &mirror_x), (&quarter, &mirror_y)];
    let mut moved = 0;
    for (m, image) in images {
        for (wi, wo) in pairs(0.8) {
            let a = m.eval_cos(wi, wo).max_channel();
            let b = m.eval_cos(image(wi), image(wo)).max_channel();
            assert!(close(a, b), "{wi:?} {wo:?}: {a} {b}");
            assert!(close(m.pdf(wi, wo), m.pdf(image(wi), image(wo))));
            // ... and not the whole-turn copy, whose lobe stays at absolute azimuths.
            let c = full.eval_cos(wi, wo).max_channel();
            moved += usize::from((a - c).abs() > 1e-3 * a.max(c).max(1e-12));
        }
    }
    assert!(
        moved >= 20,
        "only {moved} of 60 folded pairs differ from the whole turn"
    );
    // A span that is neither a whole, half nor quarter turn is refused.
    assert_eq!(
        RglMaterial::from_bytes(&azimuth_copy(&bytes, 3, -PI, -PI + 1.0)).unwrap_err(),
        RglError::BadAngles("phi_i")
    );
}

/// A spectral copy of the file `bytes`: its `rgb` table replaced by `wavelengths` (nm, an
/// uneven grid over 360-830) and `spectra`, each node's spectrum constant at the
/// luminance of its RGB.
fn grey_spectral_copy(bytes: &[u8]) -> Vec<u8> {
    let wavelengths: Vec<f32> = (0..=40).map(|k| 360.0 + 0.29375 * (k * k) as f32).collect();
    rewrite(bytes, |f| match f.name.as_str() {
        "rgb" => {
            let rgb = f.f32_values("rgb").unwrap();
            let (nodes, w) = (f.shape[3] * f.shape[4], wavelengths.len());
            let mut spectra = Vec::with_capacity(rgb.len() / 3 * w);
            for slice in rgb.chunks(3 * nodes) {
                for _ in 0..w {
                    spectra.extend((0..nodes).map(|i| {
                        let y = 0.2126 * slice[i] + 0.7152 * slice[nodes + i];
                        (y + 0.0722 * slice[2 * nodes + i]) as f32
                    }));
                }
            }
            let mut shape = f.shape.clone();
            shape[2] = w;
            Rewrite::ReplaceMany(vec![
                Out {
                    name: "wavelengths".into(),
                    dtype: 10,
                    shape: vec![w],
                    data: wavelengths.iter().flat_map(|v| v.to_le_bytes()).collect(),
                },
                Out {
                    name: "spectra".into(),
                    dtype: 10,
                    shape,
                    data: spectra.iter().flat_map(|v| v.to_le_bytes()).collect(),
                },
            ])
        }
        _ => Rewrite::Keep,
    })
}

#[test]
fn spectral_copy_has_the_luminance_of_the_rgb_file() {
    let bytes = std::fs::read(path("vch_golden_yellow_rgb.bsdf")).unwrap();
    let rgb = RglMaterial::from_bytes(&bytes).unwrap();
    let spec = RglMaterial::from_bytes(&grey_spectral_copy(&bytes)).unwrap();
    let mut compared = 0;
    for (wi, wo) in pairs(0.0).into_iter().chain(pairs(2.0)) {
        // The tabular sampler reads the same luminance and VNDF tables.
        assert_eq!(rgb.pdf(wi, wo), spec.pdf(wi, wo));
        let (a, b) = (rgb.eval_cos(wi, wo), spec.eval_cos(wi, wo));
        assert!(b.is_finite() && b.0.iter().all(|&c| c >= 0.0), "{b:?}");
        // Where no channel of the RGB file is clamped at zero, the grey spectra have its
        // luminance (to the colour matrix's rounding of its luminance weights).
        if a.0.iter().all(|&c| c > 0.0) {
            let (ya, yb) = (a.luminance(), b.luminance());
            assert!((ya - yb).abs() <= 1e-4 * ya, "{wi:?} {wo:?}: {ya} {yb}");
            compared += 1;
        }
    }
    assert!(
        compared >= 30,
        "only {compared} of 40 pairs have positive channels"
    );
    // A spectral file whose wavelengths see no visible light is refused.
    let infrared = rewrite(&grey_spectral_copy(&bytes), |f| match f.name.as_str() {
        "wavelengths" => Rewrite::Replace(Out {
            name: f.name.clone(),
            dtype: 10,
            shape: f.shape.clone(),
            data: (0..f.shape[0])
                .flat_map(|k| (1000.0 + k as f32).to_le_bytes())
                .collect(),
        }),
        _ => Rewrite::Keep,
    });
    assert_eq!(
        RglMaterial::from_bytes(&infrared).unwrap_err(),
        RglError::BadWavelengths
    );
}

#[test]
fn sampler_chi2_and_normalisation() {
    let angles = [10.0, 50.0, 80.0];
    let mut materials: Vec<(String, RglMaterial, f64)> = FILES
        .iter()
        .map(|f| (f.to_string(), RglMaterial::open(&path(f)).unwrap(), 0.4))
        .collect();
    // The anisotropic path, between two of the copy's azimuths and away from phi_i = 0.
    let bytes = std::fs::read(path("vch_golden_yellow_rgb.bsdf")).unwrap();
    let aniso = RglMaterial::from_bytes(&anisotropic_copy(&bytes, 5)).unwrap();
    materials.push(("anisotropic copy".to_string(), aniso, 2.2));
    // Folded: in the first quadrant, outside the stored azimuths of either copy.
    let half = RglMaterial::from_bytes(&azimuth_copy(&bytes, 4, -PI, 0.0)).unwrap();
    materials.push(("half-turn copy".to_string(), half, 1.0));
    let quarter = RglMaterial::from_bytes(&azimuth_copy(&bytes, 3, -PI, -PI / 2.0)).unwrap();
    materials.push(("quarter-turn copy".to_string(), quarter, 0.8));
    let threshold = ALPHA / (materials.len() * angles.len()) as f64;
    let mut failures = Vec::new();
    for (k, (f, m, phi_i)) in materials.iter().enumerate() {
        for (j, deg) in angles.iter().enumerate() {
            let wi = dir_deg(*deg, *phi_i);
            print!("{f:<28} theta_i={deg:4.1} ");
            if let Err(e) = check_sampler(m, wi, 50 + 10 * k as u64 + j as u64, threshold) {
                failures.push(format!("{f} {deg}: {e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The chi-square test of `m`'s sampler at `wi` against its own PDF (100 000 draws), and
/// the PDF's integral against the sampled-mass fraction.
fn check_sampler(m: &RglMaterial, wi: DVec3, seed: u64, threshold: f64) -> Result<(), String> {
    const N: usize = 100_000;
    let mut r = rng(seed);
    let mut samples = Vec::new();
    for _ in 0..N {
        let u = [r.gen::<f64>(), r.gen::<f64>(), r.gen::<f64>()];
        if let Some(s) = m.sample(wi, u) {
            let p = m.pdf(wi, s.wo);
            assert!(
                (p - s.pdf).abs() <= 1e-6 * s.pdf,
                "pdf {p} vs sampled {}",
                s.pdf
            );
            assert!(s.weight.is_finite());
            samples.push(s.wo);
        }
    }
    let frac = samples.len() as f64 / N as f64;
    let dom = Domain::new(DVec3::new(-wi.x, -wi.y, wi.z));
    let pdf = |w: DVec3| m.pdf(wi, w);
    let integral = dom.integrate(&pdf);
    let total: f64 = integral.iter().sum();
    let c = chi2_of_samples(&dom, &samples, N, &integral);
    let sigma = (frac * (1.0 - frac) / N as f64).sqrt();
    println!(
        "int={total:.5} frac={frac:.5} chi2={:8.1} dof={:4} p={:.4}",
        c.stat, c.dof, c.p
    );
    if c.p < threshold || (total - frac).abs() > 5.0 * sigma + 2e-3 {
        return Err(format!("p={:.3e} int={total} frac={frac}", c.p));
    }
    Ok(())
}

/// Energy: `int f |cos| dwo <= 1` by quadrature for every file.
#[test]
fn white_furnace_bound() {
    for f in FILES {
        let m = RglMaterial::open(&path(f)).unwrap();
        for deg in [0.0, 45.0, 80.0] {
            let wi = dir_deg(deg, 0.0);
            let e: f64 = Domain::new(DVec3::new(-wi.x, -wi.y, wi.z))
                .integrate(&|wo: DVec3| m.eval_cos(wi, wo).max_channel())
                .iter()
                .sum();
            println!("{f:<28} theta_i={deg:4.1} albedo(max channel)={e:.4}");
            assert!(e <= 1.0 + 2e-3, "{f} {deg}: {e}");
        }
    }
}
