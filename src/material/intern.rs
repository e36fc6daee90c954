//! Shared, `'static` copies of per-material constants that a `Copy` BSDF refers to instead
//! of carrying (a blend's pair of BSDFs, a conductor's optical constants): one copy per
//! distinct value per process, so that the `Bsdf` enum stays small (see the size test in
//! the material tests).

use std::any::Any;
use std::sync::{Mutex, OnceLock};

/// The shared copy of `x` (made once per distinct value per process; values that are not
/// equal to themselves, NaN, get a copy each).
pub fn intern<T: PartialEq + Send + Sync + 'static>(x: T) -> &'static T {
    type All = Vec<&'static (dyn Any + Send + Sync)>;
    static ALL: OnceLock<Mutex<All>> = OnceLock::new();
    let mut all = ALL
        .get_or_init(|| Mutex::new(Vec::new()))
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(p) = all
        .iter()
        .filter_map(|a| a.downcast_ref::<T>())
        .find(|p| **p == x)
    {
        return p;
    }
    let p: &'static T = Box::leak(Box::new(x));
    all.push(p);
    p
}
