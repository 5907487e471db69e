//! `fit --student-layers`: the student's depth reaches the blob, and only the depths the
//! kernel compiles are accepted.

use clap::Parser;
use diffbsdf::AnyModel;
use diffbsdf_cli::cli::{run, Cli};

const SPEC: &str = "conductor:ggx,alpha=0.3,metal=Cu";

fn args<'a>(out: &'a str, layers: &'a str) -> Vec<&'a str> {
    vec![
        "diffbsdf",
        "fit",
        SPEC,
        "--tiny",
        "--domain",
        "disk",
        "--no-eval",
        "--exact-samples",
        "20000",
        "--student-layers",
        layers,
        "--out",
        out,
    ]
}

#[test]
fn student_layers_sets_the_velocity_depth_of_the_blob() {
    let dir = std::env::temp_dir().join(format!("diffbsdf-fit-student-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("four.dbsdf");
    let cli = Cli::try_parse_from(args(out.to_str().unwrap(), "4")).unwrap();
    run(cli, &mut Vec::new()).unwrap();
    let model = AnyModel::from_blob(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(model.def().velocity.hidden_layers, 4);
    assert_eq!(model.def().velocity.width, 32);
    assert!(matches!(model, AnyModel::Velocity4x32(_)));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn student_layers_outside_the_compiled_depths_is_a_usage_error() {
    for layers in ["2", "5", "0", "x"] {
        let err = Cli::try_parse_from(args("unused.dbsdf", layers)).unwrap_err();
        assert_eq!(
            err.kind(),
            clap::error::ErrorKind::ValueValidation,
            "{layers}"
        );
    }
}
