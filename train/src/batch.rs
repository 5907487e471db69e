//! Batched, parallel forward/backward passes over an [`Mlp`]. A batch is cut into a fixed
//! number of chunks (independent of the thread count) whose gradients are summed in
//! order, so results are bit-for-bit reproducible on any machine; each chunk runs through
//! the net layer by layer in register tiles ([`Block`]).

use crate::block::Block;
use crate::mlp::Mlp;
use rayon::prelude::*;
use std::cell::RefCell;

/// Rows per chunk of work.
const CHUNK_ROWS: usize = 256;

thread_local! {
    /// Each worker thread's activations, kept between batches (no allocation per chunk).
    static BLOCK: RefCell<Block> = RefCell::new(Block::default());
}

/// Loss and parameter gradient of a batch. `inputs` holds the rows back to back;
/// `head(row, output, d_output)` returns the row's loss and writes `dL/doutput`.
pub fn loss_and_grad<F>(net: &Mlp, inputs: &[f32], head: F) -> (f64, Vec<f32>)
where
    F: Fn(usize, &[f32], &mut [f32]) -> f64 + Sync,
{
    let n_in = net.inputs();
    let n_par = net.params().len();
    let rows = inputs.len() / n_in.max(1);
    let partial: Vec<(f64, Vec<f32>)> = (0..rows.div_ceil(CHUNK_ROWS))
        .into_par_iter()
        .map(|c| {
            let mut grad = vec![0.0f32; n_par];
            let (first, end) = (c * CHUNK_ROWS, ((c + 1) * CHUNK_ROWS).min(rows));
            let x = &inputs[first * n_in..end * n_in];
            let loss = BLOCK.with_borrow_mut(|block| {
                let out = block.forward(net, x);
                let n_out = net.outputs();
                let mut d_out = vec![0.0f32; out.len()];
                let mut loss = 0.0;
                for (k, (o, d)) in out
                    .chunks_exact(n_out)
                    .zip(d_out.chunks_exact_mut(n_out))
                    .enumerate()
                {
                    loss += head(first + k, o, d);
                }
                block.backward(net, x, &d_out, &mut grad);
                loss
            });
            (loss, grad)
        })
        .collect();
    let mut total = 0.0;
    let mut grad = vec![0.0f32; n_par];
    for (l, g) in partial {
        total += l;
        grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
    }
    (total, grad)
}

/// Outputs of a batch of rows, in parallel.
pub fn forward_rows(net: &Mlp, inputs: &[f32]) -> Vec<f32> {
    let n_in = net.inputs();
    let n_out = net.outputs();
    let rows = inputs.len() / n_in.max(1);
    let mut out = vec![0.0f32; rows * n_out];
    out.par_chunks_mut(CHUNK_ROWS * n_out)
        .enumerate()
        .for_each(|(c, dst)| {
            let rows_here = dst.len() / n_out.max(1);
            let x = &inputs[c * CHUNK_ROWS * n_in..(c * CHUNK_ROWS + rows_here) * n_in];
            BLOCK.with_borrow_mut(|block| dst.copy_from_slice(block.forward(net, x)));
        });
    out
}
