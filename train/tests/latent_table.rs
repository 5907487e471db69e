//! The latent table (docs/math.md §6.5): fitted in front of a tiny fit of rough copper on
//! the half-vector chart in warped standard coordinates (the default recipe's chart and
//! coordinates for a BRDF), it lowers the relative variance the evaluation measures on its
//! own grid and seed, the model stays exact on the exactness sweep (f32 and f16), the
//! stored table survives the blob, and removing it gives back the flow alone.

use diffbsdf::{AnyModel, Domain, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::latent_table::{fit_latent_table, without_table, TableConfig};
use diffbsdf_train::metrics::{evaluate, EvalConfig};
use diffbsdf_train::{fit_material, FitConfig, ModelExt, Silent};

#[test]
fn the_table_lowers_the_measured_variance_and_stays_exact() {
    let spec = "conductor:ggx,alpha=0.3,metal=Cu";
    let material = parse_spec(spec).unwrap();
    let mut cfg = FitConfig::tiny(Domain::HalfVector, 3);
    cfg.def.standardized = true;
    cfg.def.standard_warp = true;
    let flow = fit_material(material.as_ref(), "table", &cfg, &Silent)
        .unwrap()
        .model;
    assert_eq!(flow.def().latent_table, None);
    let table_cfg = TableConfig {
        draws_per_slice: 20_000,
        ..TableConfig::DEFAULT
    };
    let (tabled, fit) = fit_latent_table(&flow, material.as_ref(), &table_cfg, 5).unwrap();
    // On its own draws the table lowers the flow's relative variance.
    assert!(
        fit.rv_table < 0.9 * fit.rv_flow,
        "in-sample RV {} -> {}",
        fit.rv_flow,
        fit.rv_table
    );
    assert_eq!(
        tabled.def().latent_table,
        Some(diffbsdf::TableGrid::BlendedSlices)
    );

    // Through the blob and back, and without the table again.
    let bytes = tabled.blob(Precision::F32).unwrap();
    assert_eq!(
        AnyModel::from_blob(&bytes)
            .unwrap()
            .blob(Precision::F32)
            .unwrap(),
        bytes
    );
    assert_eq!(
        without_table(&tabled)
            .unwrap()
            .blob(Precision::F32)
            .unwrap(),
        flow.blob(Precision::F32).unwrap()
    );

    let eval = EvalConfig {
        samples: 1 << 14,
        exact_samples: 40_000,
        kl: None,
        timing_calls: 0,
        ..EvalConfig::default()
    };
    let before = evaluate(&flow, material.as_ref(), &eval);
    let after = evaluate(&tabled, material.as_ref(), &eval);
    assert!(
        after.learned.rv_mean < 0.9 * before.learned.rv_mean,
        "mean RV {} -> {}",
        before.learned.rv_mean,
        after.learned.rv_mean
    );
    let exact = after.exactness.expect("the sweep ran");
    assert!(exact.passes(), "{}", exact.summary());
}
