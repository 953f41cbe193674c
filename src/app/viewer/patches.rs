//! The viewer's forest patches (`--forest-patches`): made once every level is in.

use super::Viewer;
use anyhow::Result;

impl Viewer {
    /// Forest patches as `--forest-patches` asks, once every level is in: baked (or read from
    /// the cache) the first time, which holds the window for the bake's measurement (15-25 s
    /// on lavapipe, once per layout).
    pub(super) fn patches_as_asked(&mut self) -> Result<()> {
        if !self.settings.foliage.patches {
            self.world.drop_patches();
            return Ok(());
        }
        if self.world.patches().is_none() {
            let gpu = &self.win.gpu;
            let colour =
                crate::runtime::levels::Measurer::colour(&crate::measure::GpuMeasurer, gpu);
            if let Err(e) = self.world.ensure_patches(gpu, colour.as_ref()) {
                // Said once in the panel; the trees are drawn as they were.
                self.baking.bake_error = Some(format!("forest patches: {e:#}"));
                self.settings.foliage.patches = false;
            }
        }
        Ok(())
    }
}
