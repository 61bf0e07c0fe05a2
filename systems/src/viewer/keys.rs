//! The viewer's keys (see the [module docs](super)): the count, the seed, and the
//! colour, mesh, footprint and paint modes.

use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};

use super::{Viewer, set_sampling};
use crate::gpu::{ColorMode, Footprint, GpuSplats, MeshMode, StyleChoice};

impl Viewer {
    pub(super) fn key(&mut self, key: &Key, event_loop: &ActiveEventLoop) {
        match key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::ArrowUp) => {
                let max = self
                    .engine
                    .world
                    .get_resource::<GpuSplats>()
                    .map_or(usize::MAX, |g| {
                        crate::gpu::buffers::max_samples(&g.ctx.device)
                    });
                set_sampling(&mut self.engine, self.mesh_entity, |s| {
                    s.count = s.count.saturating_mul(2).clamp(1, max)
                });
                self.refit_colors = true;
            }
            Key::Named(NamedKey::ArrowDown) => {
                set_sampling(&mut self.engine, self.mesh_entity, |s| s.count /= 2);
                self.refit_colors = true;
            }
            Key::Character(c) => match c.as_str() {
                "s" | "S" => set_sampling(&mut self.engine, self.mesh_entity, |s| {
                    s.seed = s.seed.wrapping_add(1)
                }),
                "c" | "C" => {
                    self.style.color_mode = match self.style.color_mode {
                        ColorMode::Density => ColorMode::Segment,
                        ColorMode::Segment => ColorMode::Constant,
                        ColorMode::Constant => ColorMode::Density,
                    }
                }
                "m" | "M" => {
                    self.style.mesh_mode = match self.style.mesh_mode {
                        MeshMode::Plain => MeshMode::Segments,
                        MeshMode::Segments => MeshMode::None,
                        MeshMode::None => MeshMode::Plain,
                    }
                }
                "p" | "P" => self.repaint(self.paint.next_style()),
                "b" | "B" => self.repaint(self.paint.next_brush()),
                "f" | "F" => {
                    self.style.footprint = match self.style.footprint {
                        Footprint::Disc => Footprint::Gaussian,
                        Footprint::Gaussian => Footprint::Glyph,
                        Footprint::Glyph => Footprint::Disc,
                    }
                }
                _ => {}
            },
            _ => {}
        }
    }

    /// Switches to `paint` (printing it), except with `--lod`, which stipple and
    /// strokes do not support yet.
    fn repaint(&mut self, paint: StyleChoice) {
        if self.lod_max.is_some() && paint.kind().is_some() {
            println!(
                "style: {paint} does not support --lod yet; still {}",
                self.paint
            );
        } else {
            self.paint = paint;
            println!("style: {paint}");
        }
    }
}
