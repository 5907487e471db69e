//! Batched, parallel forward/backward passes over an [`Mlp`]. A batch is cut into a fixed
//! number of chunks (independent of the thread count) whose gradients are summed in
//! order, so results are bit-for-bit reproducible on any machine.

use crate::mlp::{Mlp, Tape};
use rayon::prelude::*;

/// Rows per chunk of work.
const CHUNK_ROWS: usize = 256;

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
            let mut tape = Tape::default();
            let mut scratch = [Vec::new(), Vec::new()];
            let mut d_out = vec![0.0f32; net.outputs()];
            let mut loss = 0.0;
            for r in c * CHUNK_ROWS..((c + 1) * CHUNK_ROWS).min(rows) {
                let x = &inputs[r * n_in..(r + 1) * n_in];
                let out = net.forward_tape(x, &mut tape);
                loss += head(r, out, &mut d_out);
                net.backward(x, &tape, &d_out, &mut grad, &mut scratch);
            }
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
            let mut tape = Tape::default();
            for (k, o) in dst.chunks_exact_mut(n_out).enumerate() {
                let r = c * CHUNK_ROWS + k;
                let y = net.forward_tape(&inputs[r * n_in..(r + 1) * n_in], &mut tape);
                o.copy_from_slice(y);
            }
        });
    out
}
