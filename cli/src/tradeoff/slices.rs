//! PDF slice images: for a few `wi` (incl. grazing), the target density
//! `Y(f) |cos theta_o| / integral` beside the learned model's PDF (by its exact inverse),
//! on a shared logarithmic colour scale. One row per `wi`; columns: target and learned over
//! the upper hemisphere, then (sphere models) target and learned over the lower one. Each
//! hemisphere is drawn in its orthographic projection `(wo.x, wo.y)`, +x to the right.

use super::slice_labels::{self, Layout};
use super::sweep::SweepError;
use diffbsdf::AnyModel;
use diffbsdf_materials::{from_spherical, DVec3, Material};
use diffbsdf_train::metrics::sampler::to_glam;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

/// Pixels per panel side.
pub const PANEL: usize = 160;
const GAP: usize = 6;
/// Decades of density below each row's peak that the colour scale spans.
pub const DECADES: f64 = 4.0;
/// Polar angles of the rows, degrees: normal, oblique, grazing (and from below on the
/// sphere for transmissive materials).
pub const THETA_DISK: [f64; 3] = [0.0, 60.0, 89.0];
/// Rows of sphere models of transmissive materials.
pub const THETA_SPHERE: [f64; 4] = [0.0, 60.0, 89.0, 150.0];

/// `integral Y(f) |cos theta_o| dw` by midpoint quadrature over the sphere.
fn target_norm(material: &dyn Material, wi: DVec3) -> f64 {
    let (nt, np) = (256usize, 256usize);
    let (dt, dp) = (PI / nt as f64, 2.0 * PI / np as f64);
    (0..nt)
        .map(|i| {
            let t = (i as f64 + 0.5) * dt;
            (0..np)
                .map(|j| {
                    let wo = from_spherical(t, (j as f64 + 0.5) * dp);
                    let p = material.eval_luminance(wi, wo) * wo.z.abs();
                    if p.is_finite() {
                        p.max(0.0)
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
                * t.sin()
                * dt
                * dp
        })
        .sum()
}

/// The direction at pixel `(px, py)` of a hemisphere panel, if inside the disk.
fn pixel_direction(px: usize, py: usize, upper: bool) -> Option<DVec3> {
    let x = 2.0 * (px as f64 + 0.5) / PANEL as f64 - 1.0;
    let y = 1.0 - 2.0 * (py as f64 + 0.5) / PANEL as f64;
    let r2 = x * x + y * y;
    if r2 >= 1.0 {
        return None;
    }
    let z = (1.0 - r2).sqrt();
    Some(DVec3::new(x, y, if upper { z } else { -z }))
}

/// Densities of one panel (row-major); `None` outside the disk.
fn panel(f: &(dyn Fn(DVec3) -> f64 + Sync), upper: bool) -> Vec<Option<f64>> {
    (0..PANEL * PANEL)
        .into_par_iter()
        .map(|k| pixel_direction(k % PANEL, k / PANEL, upper).map(f))
        .collect()
}

fn colour(d: Option<f64>, top: f64) -> [u8; 3] {
    let Some(d) = d else { return [255, 255, 255] };
    let t = if d > 0.0 && d.is_finite() {
        ((d.log10() - (top - DECADES)) / DECADES).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let c = colorous::INFERNO.eval_continuous(t);
    [c.r, c.g, c.b]
}

/// Writes the slice image of `model` against `material` to `path` (PNG), and beside it
/// the same image with its labels (`slice_labels`, `.svg`).
pub fn write_png(
    model: &AnyModel,
    material: &dyn Material,
    sphere: bool,
    path: &Path,
) -> Result<(), SweepError> {
    let both = sphere && material.is_transmissive();
    let thetas: &[f64] = if both { &THETA_SPHERE } else { &THETA_DISK };
    let sides: &[bool] = if both { &[true, false] } else { &[true] };
    let cols = 2 * sides.len();
    let (w, h) = (
        cols * PANEL + (cols - 1) * GAP,
        thetas.len() * PANEL + (thetas.len() - 1) * GAP,
    );
    let mut img = vec![255u8; w * h * 3];
    for (row, &theta) in thetas.iter().enumerate() {
        let wi = from_spherical(theta.to_radians(), 0.0);
        let z = target_norm(material, wi).max(1e-300);
        let target = |wo: DVec3| (material.eval_luminance(wi, wo) * wo.z.abs()).max(0.0) / z;
        let learned = |wo: DVec3| model.pdf(to_glam(wi), to_glam(wo)) as f64;
        let mut panels = Vec::new();
        for &upper in sides {
            panels.push(panel(&target, upper));
            panels.push(panel(&learned, upper));
        }
        let top = panels
            .iter()
            .flatten()
            .flatten()
            .filter(|d| d.is_finite() && **d > 0.0)
            .fold(f64::MIN, |m, d| m.max(d.log10()));
        for (col, p) in panels.iter().enumerate() {
            for (k, d) in p.iter().enumerate() {
                let (x, y) = (
                    col * (PANEL + GAP) + k % PANEL,
                    row * (PANEL + GAP) + k / PANEL,
                );
                let at = 3 * (y * w + x);
                img[at..at + 3].copy_from_slice(&colour(*d, top));
            }
        }
    }
    let png_err =
        |e: png::EncodingError| SweepError::Image(path.display().to_string(), e.to_string());
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(png_err)?;
        writer.write_image_data(&img).map_err(png_err)?;
        writer.finish().map_err(png_err)?;
    }
    let layout = Layout {
        model: path.file_stem().and_then(|s| s.to_str()).unwrap_or(""),
        size: (w, h),
        panel: PANEL,
        gap: GAP,
        thetas,
        sides,
        decades: DECADES,
    };
    let labelled = slice_labels::svg(&layout, &bytes);
    let io = |p: &Path| {
        let p = p.display().to_string();
        move |e: std::io::Error| SweepError::Image(p, e.to_string())
    };
    std::fs::write(path, &bytes).map_err(io(path))?;
    let svg = path.with_extension("svg");
    std::fs::write(&svg, labelled).map_err(io(&svg))
}
