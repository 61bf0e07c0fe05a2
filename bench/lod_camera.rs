//! The camera of the level-of-detail benches (`lod`, `lod_ecs`): 1280 x 720, a
//! 45-degree vertical field of view, 2.5 bounding radii from the mesh's centre, back
//! faces culled, the multiplier clamped at 4, and the reference area that of a surface
//! facing the camera at the centre (multiplier 1 there).

use glam::DVec3;
use strata_engine::sample::lod::ViewLod;
use strata_systems::scene::Scene;

const WIDTH: f64 = 1280.0;
const HEIGHT: f64 = 720.0;
const FOV_Y: f64 = std::f64::consts::FRAC_PI_4;

/// The benches' camera around one mesh.
#[derive(Clone, Copy, Debug)]
pub struct LodCamera {
    /// The centre of the mesh's bounding box, where the camera looks.
    pub centre: DVec3,
    /// The first frame's eye: 2.5 bounding radii from the centre along +z.
    pub start: DVec3,
    /// Projected area per unit area (pixels^2) of a surface facing the camera at the
    /// centre from `start`.
    pub reference: f64,
}

impl LodCamera {
    /// The camera around the mesh with vertex positions `positions`.
    pub fn around(positions: &[DVec3]) -> Self {
        let (lo, hi) = positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let centre = 0.5 * (lo + hi);
        let radius = positions
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f64::max);
        let distance = 2.5 * radius;
        let focal = HEIGHT / (2.0 * (FOV_Y / 2.0).tan());
        Self {
            centre,
            start: centre + DVec3::new(0.0, 0.0, distance),
            reference: focal * focal / (distance * distance),
        }
    }

    /// The view from `eye`, looking at the centre.
    pub fn view(&self, eye: DVec3) -> ViewLod {
        let proj =
            glam::dcamera::rh::proj::directx::perspective(FOV_Y, WIDTH / HEIGHT, 0.001, 1000.0);
        let look = glam::dcamera::rh::view::look_at_mat4(eye, self.centre, DVec3::Y);
        ViewLod {
            clip_from_world: proj * look,
            eye,
            focal_pixels: HEIGHT / (2.0 * (FOV_Y / 2.0).tan()),
            reference: self.reference,
            max: 4.0,
            cull_back_faces: true,
        }
    }

    /// Frame `t` of a dolly: the distance to the centre times `factor^t`.
    pub fn dolly(&self, factor: f64, t: i32) -> ViewLod {
        self.view(self.centre + (self.start - self.centre) * factor.powi(t))
    }
}

/// The level-of-detail benches' scene with sampling seed `seed`: the bunny with its 3:1
/// field (`stanford-bunny-anisotropic.ron`), or the default scene when the shared
/// meshes are absent; with the bundled config's file name.
pub fn lod_scene(seed: u64) -> Result<(&'static str, Scene), Box<dyn std::error::Error>> {
    let file = match crate::shared_mesh_dir() {
        Ok(_) => "stanford-bunny-anisotropic.ron",
        Err(e) => {
            eprintln!("{e}; using the default scene");
            "default.ron"
        }
    };
    let (_, mut config) = crate::bundled_scenes(&[("scene", file)])?.remove(0);
    config.sampling.seed = seed;
    Ok((file, Scene::build(&config)?))
}
