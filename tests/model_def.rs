//! The model definition is the one description of a model's layers: the layer chain it
//! reports is consistent, and the kernel's parameter visitor covers exactly the parameters
//! it counts, in blob order.

use diffbsdf::{AnyModel, Domain, Layer, ModelDef, Net};

fn chain(def: &ModelDef, net: Net) -> Vec<Layer> {
    (0..def.layer_count(net))
        .map(|i| def.layer(net, i).expect("layer within layer_count"))
        .collect()
}

fn definitions() -> Vec<ModelDef> {
    let mut defs = Vec::new();
    for base in [ModelDef::paper_disk(), ModelDef::paper_sphere()] {
        for domain in [Domain::Disk, Domain::Sphere, Domain::Equatorial] {
            let mut def = base;
            def.domain = domain;
            defs.push(def);
        }
    }
    defs
}

#[test]
fn layer_chain_connects_inputs_to_outputs() {
    for def in definitions() {
        for net in Net::ALL {
            let layers = chain(&def, net);
            assert_eq!(layers.len(), def.net_shape(net).hidden_layers as usize + 1);
            assert_eq!(layers[0].inputs, def.net_inputs(net));
            assert_eq!(layers.last().map(|l| l.outputs), Some(def.net_outputs(net)));
            for pair in layers.windows(2) {
                assert_eq!(pair[0].outputs, pair[1].inputs, "{def:?} {net:?}");
                assert!(pair[0].activated);
            }
            assert!(
                !layers.last().is_some_and(|l| l.activated),
                "readout is linear"
            );
            assert!(def.layer(net, layers.len()).is_none());
            let sum: usize = layers.iter().map(Layer::param_count).sum();
            assert_eq!(sum, def.net_param_count(net));
        }
        assert_eq!(
            def.param_count(),
            def.net_param_count(Net::Base) + def.net_param_count(Net::Velocity)
        );
    }
}

#[test]
fn velocity_inputs_are_features_time_and_encoding() {
    for def in definitions() {
        let expected = def.domain.feature_count() + 1 + def.velocity.encoding_len();
        assert_eq!(def.net_inputs(Net::Velocity), expected);
        assert_eq!(def.net_inputs(Net::Base), def.base.encoding_len());
    }
}

#[test]
fn parameter_visitor_covers_exactly_the_counted_parameters() {
    for def in definitions() {
        let n = def.param_count();
        // Distinct, finite values: a visitor that skipped, repeated or reordered a
        // parameter would not give them back in the same order.
        let params: Vec<f32> = (0..n).map(|i| i as f32 * 1e-3 - 1.0).collect();
        let model = AnyModel::from_params(def, &params).expect("paper shapes load");
        let mut back = vec![f32::NAN; n + 7];
        assert_eq!(model.params(&mut back), Ok(n));
        assert_eq!(&back[..n], &params[..]);
        assert!(
            back[n..].iter().all(|x| x.is_nan()),
            "wrote past param_count"
        );
        let short = AnyModel::from_params(def, &params[..n - 1]);
        assert!(short.is_err());
    }
}
