//! The viewer's level of detail (`strata view --lod`): the mesh entity's [`Lod`]
//! follows the window's camera, and a point budget's base count reaches the splats.

use crate::ecs::{Lod, LodState};
use crate::gpu::SplatLod;
use strata_engine::sample::LodPool;

use super::Viewer;

impl Viewer {
    /// With `--lod`: points the mesh entity's [`Lod`] at the current camera.
    pub(super) fn follow_camera(&mut self) {
        let (Some(max), Some(camera), Some(gpu)) = (self.lod_max, &self.camera, &self.gpu) else {
            return;
        };
        let size = (gpu.config.width, gpu.config.height);
        let base = self.sampling().count.min(u32::MAX as usize) as u32;
        let mut lod = *self
            .lod
            .get_or_insert_with(|| SplatLod::for_camera(camera, size.1, base as f32, max));
        lod.base = base as f32;
        lod.expanded = base as f32;
        self.lod = Some(lod);
        self.style.lod = Some(lod);
        let component = Lod {
            view: lod.view(camera, size),
            base,
            budget: LodPool::room_for(base, self.lod_shown, f64::from(max)),
            shown: self.lod_shown,
        };
        let mut entity = self.engine.world.entity_mut(self.mesh_entity);
        if !entity.contains::<LodState>() {
            entity.insert(LodState::default());
        }
        entity.insert(component);
    }

    /// With a point budget: draws with the base count the engine's update used.
    pub(super) fn draw_with_budget(&mut self) {
        let (Some(_), Some(lod)) = (self.lod_shown, self.style.lod.as_mut()) else {
            return;
        };
        if let Some(state) = self.engine.world.get::<LodState>(self.mesh_entity) {
            lod.base = state.base as f32;
        }
    }
}
