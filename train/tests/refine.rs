//! The variance refinement of the student (docs/math.md §11, (67)-(69)): on a tiny fit of
//! rough copper on the half-vector chart, in warped standard coordinates (the default
//! recipe's chart and coordinates), a short refinement lowers the relative variance the
//! evaluation measures on its own grid and seed, and the refined model stays exact on
//! the exactness sweep, f32 and f16. Off, it returns the model unchanged.

use diffbsdf::{Domain, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::metrics::{evaluate, EvalConfig};
use diffbsdf_train::refine::{refine, RefineConfig};
use diffbsdf_train::{fit_material, FitConfig, ModelExt, Silent};

#[test]
fn refinement_lowers_the_measured_variance_and_stays_exact() {
    let material = parse_spec("conductor:ggx,alpha=0.3,metal=Cu").unwrap();
    let mut cfg = FitConfig::tiny(Domain::HalfVector, 3);
    cfg.def.standardized = true;
    cfg.def.standard_warp = true;
    let fitted = fit_material(material.as_ref(), "refine", &cfg, &Silent).unwrap();

    let off = refine(
        &fitted.model,
        material.as_ref(),
        &RefineConfig::OFF,
        1,
        &Silent,
    )
    .unwrap();
    assert!(!off.1.kept);
    assert_eq!(
        off.0.blob(Precision::F32).unwrap(),
        fitted.model.blob(Precision::F32).unwrap()
    );

    let refine_cfg = RefineConfig {
        iters: 100,
        incidences: 16,
        lr: 1e-3,
        target_share: 0.5,
        ..RefineConfig::default()
    };
    let (refined, what) =
        refine(&fitted.model, material.as_ref(), &refine_cfg, 1, &Silent).unwrap();
    assert!(
        what.kept && what.loss_after < 0.95 * what.loss_before,
        "validation ln(1 + RV) {} -> {}",
        what.loss_before,
        what.loss_after
    );

    let eval = EvalConfig {
        samples: 1 << 14,
        exact_samples: 40_000,
        kl: None,
        timing_calls: 0,
        ..EvalConfig::default()
    };
    let before = evaluate(&fitted.model, material.as_ref(), &eval);
    let after = evaluate(&refined, material.as_ref(), &eval);
    assert!(
        after.learned.rv_mean < 0.95 * before.learned.rv_mean,
        "mean RV {} -> {}",
        before.learned.rv_mean,
        after.learned.rv_mean
    );
    let exact = after.exactness.expect("the sweep ran");
    assert!(exact.passes(), "{}", exact.summary());
}
