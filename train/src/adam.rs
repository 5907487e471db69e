//! Adam (Kingma & Ba 2015) with bias correction.

/// Adam state for one parameter vector.
#[derive(Clone, Debug)]
pub struct Adam {
    m: Vec<f32>,
    v: Vec<f32>,
    step: i32,
    beta1: f32,
    beta2: f32,
    eps: f32,
}

impl Adam {
    /// State for `n` parameters with the usual `beta1 = 0.9, beta2 = 0.999, eps = 1e-8`.
    pub fn new(n: usize) -> Self {
        Adam {
            m: vec![0.0; n],
            v: vec![0.0; n],
            step: 0,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }

    /// One update of `params` along `grad` with learning rate `lr`.
    pub fn update(&mut self, params: &mut [f32], grad: &[f32], lr: f32) {
        self.step += 1;
        // m <- b1 m + (1-b1) g;  v <- b2 v + (1-b2) g^2;  p -= lr m_hat / (sqrt(v_hat) + eps)
        let c1 = 1.0 - self.beta1.powi(self.step);
        let c2 = 1.0 - self.beta2.powi(self.step);
        for (((p, g), m), v) in params
            .iter_mut()
            .zip(grad)
            .zip(&mut self.m)
            .zip(&mut self.v)
        {
            *m = self.beta1 * *m + (1.0 - self.beta1) * g;
            *v = self.beta2 * *v + (1.0 - self.beta2) * g * g;
            *p -= lr * (*m / c1) / ((*v / c2).sqrt() + self.eps);
        }
    }
}

/// Cosine decay from `lr` to `lr * floor` over `total` steps.
pub fn cosine_lr(lr: f32, floor: f32, step: usize, total: usize) -> f32 {
    let frac = step as f32 / total.max(1) as f32;
    let c = 0.5 * (1.0 + (std::f32::consts::PI * frac.min(1.0)).cos());
    lr * (floor + (1.0 - floor) * c)
}
