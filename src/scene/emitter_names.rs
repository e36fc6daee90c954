//! An emitter of a scene description named where the file defines it, for the error that
//! refuses it (an emitter whose power overflows single precision: `light::TooBright`).

use super::SceneDesc;
use crate::light::TooBright;

impl SceneDesc {
    /// "place: emitter: what is wrong" for an emitter whose power overflows.
    pub(super) fn too_bright(&self, e: TooBright) -> String {
        let at = |s: &Option<String>| s.as_deref().map(|s| format!("{s}: ")).unwrap_or_default();
        let who = match e {
            TooBright::Area { material, .. } => {
                format!(
                    "{} (emitter)",
                    self.materials[material as usize].described()
                )
            }
            TooBright::Point { index, .. } => {
                format!("{}point light", at(&self.point_lights[index].source))
            }
            TooBright::Env { .. } => format!(
                "{}environment",
                at(&self.environment.as_ref().and_then(|e| e.source.clone()))
            ),
            TooBright::Total { .. } => format!("scene {}", self.name),
        };
        format!("{who}: {}", e.describe())
    }
}
