//! The C ABI's step convention over the kernel's shape dispatch ([`diffbsdf::AnyModel`]).

use diffbsdf::AnyModel;

/// `steps`, or the model's default step count when the caller passes 0 (the C ABI's
/// convention, stated in `include/diffbsdf.h`).
pub(crate) fn resolve_steps(model: &AnyModel, steps: u32) -> u32 {
    if steps == 0 {
        model.def().default_steps as u32
    } else {
        steps
    }
}
