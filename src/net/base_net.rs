//! The base net: `wi` encoding -> the four parameters of `p0(x0 | wi)`.

use super::activation::silu_layer;
use super::dense::{Dense, Readout};
use crate::spec::BASE_OUTPUTS;

/// `E` encoding inputs, `M + 1` hidden layers of width `W`, 4 outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseNet<const E: usize, const W: usize, const M: usize> {
    /// The first hidden layer, over the `wi` encoding.
    pub first: Dense<E, W>,
    /// The further hidden layers.
    pub mid: [Dense<W, W>; M],
    /// The readout: the four base parameters.
    pub out: Readout<W, BASE_OUTPUTS>,
}

impl<const E: usize, const W: usize, const M: usize> BaseNet<E, W, M> {
    /// Every parameter zero.
    pub const ZERO: Self = BaseNet {
        first: Dense::ZERO,
        mid: [Dense::ZERO; M],
        out: Readout::ZERO,
    };

    /// The raw outputs (locations and log-scales; see `base::BaseDist::from_net`).
    #[inline(always)]
    pub fn forward(&self, enc: &[f32; E]) -> [f32; BASE_OUTPUTS] {
        let mut h = self.first.forward(enc);
        silu_layer(&mut h);
        for layer in &self.mid {
            h = layer.forward(&h);
            silu_layer(&mut h);
        }
        self.out.forward(&h)
    }

    pub(crate) fn visit_mut(&mut self, f: &mut impl FnMut(&mut f32)) {
        self.first.visit_mut(f);
        for layer in self.mid.iter_mut() {
            layer.visit_mut(f);
        }
        self.out.visit_mut(f);
    }

    /// Reads every parameter in the order of [`BaseNet::visit_mut`].
    pub(crate) fn visit(&self, f: &mut impl FnMut(f32)) {
        self.first.visit(f);
        for layer in self.mid.iter() {
            layer.visit(f);
        }
        self.out.visit(f);
    }
}
