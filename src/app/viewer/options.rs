//! The viewer's options from `lodlab view`'s command line (and the web page's, from its
//! manifest).

use super::ViewOptions;
use crate::scene::LodMethod;

impl ViewOptions {
    /// What `lodlab view` with these options opens (also the web page's view, from its
    /// manifest).
    pub fn from_args(
        a: crate::app::cli::ViewArgs,
        inputs: &crate::runtime::spec::BakeInputs,
    ) -> ViewOptions {
        ViewOptions {
            spec: a.scene.spec(inputs),
            width: a.size.0,
            height: a.size.1,
            samples: a.msaa,
            screenshot: a.screenshot,
            frames: a.frames,
            lod: a.lod.shot_lod(LodMethod::AS_IS),
        }
    }
}
