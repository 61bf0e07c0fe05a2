//! Scene configuration files: what to sample and how, as RON.
//!
//! ```ron
//! (
//!     mesh: Shape(Plane(size: 1.0, resolution: 64)),   // or File("../shared/meshes/spot.obj")
//!     field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 4.0, density: 1.0),
//!     sampling: (count: 20000, seed: 7),
//!     curve: (max_cell_share: 0.0000152587890625),        // optional, see CurveOptions
//!     surface: (min_segment_faces: 16, angle_criterion: Mean), // optional
//! )
//! ```
//!
//! Unknown fields are errors (a typo must not be silently ignored); omitted optional
//! sections take their defaults, which are the engine's. Relative file paths are
//! relative to the config file. The `segment`, `param`, `curve` and `surface` sections
//! together are the engine's [`SurfaceOptions`], every field of it, mapped in one place:
//! [`SceneConfig::surface_options`].

mod messages;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use strata_engine::curve::CurveOptions;
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes::Shape;
use strata_engine::param::ParamOptions;
use strata_engine::segment::SegmentOptions;
use strata_engine::surface::{AngleCriterion, SurfaceOptions};

/// A scene: a mesh, a tensor field on it, and sampling settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// The surface to sample.
    pub mesh: MeshSource,
    /// The tensor field. Default: isotropic, density 1.
    #[serde(default = "default_field")]
    pub field: FieldSpec,
    /// Sample count and seed.
    #[serde(default)]
    pub sampling: SamplingConfig,
    /// Adaptive Hilbert cell settings.
    #[serde(default)]
    pub curve: CurveOptions,
    /// Segmentation settings (beta, sigma, seed).
    #[serde(default)]
    pub segment: SegmentOptions,
    /// Parameterization settings (gamma, isotropy threshold).
    #[serde(default)]
    pub param: ParamOptions,
    /// When invalid segments stop being split, and which angle must stay under gamma.
    #[serde(default)]
    pub surface: SurfaceConfig,
    /// Where the mesh is placed in the world (applied to the samples, so changing it
    /// only reruns sampling). Default: identity.
    #[serde(default)]
    pub transform: TransformConfig,
}

/// The settings of the surface preprocessing as a whole: the fields of
/// [`SurfaceOptions`] that are not in its `segment`, `param` and `curve` parts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceConfig {
    /// Segments with fewer faces are not split further but parameterized with the
    /// isotropic fallback. Range >= 1; default: the engine's, 16.
    pub min_segment_faces: usize,
    /// The angle between the mapped field and the u axis that must stay under
    /// `param.gamma`: `Mean`, the area-weighted mean over the segment (section 5.2), or
    /// `Max`, the largest per-face angle (section 7.3.1; splits more). Default: the
    /// engine's, `Mean`.
    pub angle_criterion: AngleCriterion,
    /// Vertices of anisotropy below this take a smooth direction before segmentation,
    /// so isotropic regions make no singularities. Range >= 1, 1 turning it off;
    /// default: the engine's, 1.1. A field isotropic everywhere is covered with
    /// normal-cone charts instead of field-aligned segments.
    pub isotropy_threshold: f64,
    /// Half-angle (radians) of the normal cones of a fully isotropic field's charts:
    /// larger makes fewer, more distorted charts. Range (0, pi]; default: the
    /// engine's, 60 degrees.
    pub chart_angle: f64,
    /// Whether neighbouring pieces of a split segment are merged back where their
    /// union parameterizes validly: fewer, larger segments. Default: the engine's,
    /// true.
    pub merge_pieces: bool,
}

impl Default for SurfaceConfig {
    fn default() -> Self {
        let engine = SurfaceOptions::default();
        Self {
            min_segment_faces: engine.min_segment_faces,
            angle_criterion: engine.angle_criterion,
            isotropy_threshold: engine.isotropy_threshold,
            chart_angle: engine.chart_angle,
            merge_pieces: engine.merge_pieces,
        }
    }
}

/// A similarity transform of the mesh: scale, then rotate, then translate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransformConfig {
    /// Translation in world units. Default (0, 0, 0).
    pub translation: [f64; 3],
    /// Rotation as Euler angles in degrees about x, then y, then z. Default (0, 0, 0).
    pub rotation_deg: [f64; 3],
    /// Uniform scale, finite and > 0. Default 1.
    pub scale: f64,
}

impl Default for TransformConfig {
    fn default() -> Self {
        Self {
            translation: [0.0; 3],
            rotation_deg: [0.0; 3],
            scale: 1.0,
        }
    }
}

impl TransformConfig {
    /// The transform as an affine map.
    pub fn to_affine(&self) -> glam::DAffine3 {
        let [x, y, z] = self.rotation_deg.map(f64::to_radians);
        glam::DAffine3::from_scale_rotation_translation(
            glam::DVec3::splat(self.scale),
            glam::DQuat::from_euler(glam::EulerRot::XYZ, x, y, z),
            glam::DVec3::from(self.translation),
        )
    }

    /// Checks that every value is finite and the scale positive.
    pub fn validate(&self) -> Result<(), String> {
        let finite = self
            .translation
            .iter()
            .chain(&self.rotation_deg)
            .all(|v| v.is_finite());
        if !finite {
            return Err("transform `translation` and `rotation_deg` must be finite".to_owned());
        }
        if !(self.scale > 0.0 && self.scale.is_finite()) {
            return Err(format!(
                "transform `scale` = {} must be finite and > 0",
                self.scale
            ));
        }
        Ok(())
    }
}

/// Where the mesh comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MeshSource {
    /// An OBJ or PLY file; a relative path is relative to the config file's folder.
    File(PathBuf),
    /// A built-in procedural shape.
    Shape(Shape),
}

/// How many samples to draw, and with which seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SamplingConfig {
    /// Number of samples per frame (any value >= 0). Default 10 000.
    pub count: u64,
    /// Random seed; the same seed gives the same samples. Default 1.
    pub seed: u64,
}

impl Default for SamplingConfig {
    fn default() -> Self {
        Self {
            count: 10_000,
            seed: 1,
        }
    }
}

fn default_field() -> FieldSpec {
    FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
        density: 1.0,
    }
}

/// Errors reading a scene file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a valid scene.
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What was wrong or expected.
        message: String,
    },
    /// The scene parsed but a value is out of range.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The scene parsed but a value is out of range; the option it names was found in
    /// the file at this line and column.
    #[error("{path}:{line}:{column}: {message}")]
    InvalidAt {
        /// The file.
        path: PathBuf,
        /// 1-based line of the option's name.
        line: usize,
        /// 1-based column of the option's name.
        column: usize,
        /// What is wrong.
        message: String,
    },
}

/// Where in `text` the option that a validation `message` names is set: the first
/// word of the message that occurs in `text` as a RON key (`word:`), preferring a word
/// in backticks. 1-based line and column (in characters), or `None`.
fn locate_option(text: &str, message: &str) -> Option<(usize, usize)> {
    let quoted = message.split('`').skip(1).step_by(2);
    let words = message
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.len() > 1 && w.chars().next().is_some_and(|c| c.is_ascii_lowercase()));
    quoted.chain(words).find_map(|word| {
        text.match_indices(word).find_map(|(at, _)| {
            let before = text[..at].chars().next_back();
            let after = text[at + word.len()..].trim_start().starts_with(':');
            let boundary = before.is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '_'));
            (after && boundary).then(|| {
                let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
                let line = text[..at].matches('\n').count() + 1;
                (line, text[line_start..at].chars().count() + 1)
            })
        })
    })
}

impl SceneConfig {
    /// Parses a scene from RON text (after a UTF-8 byte-order mark, if any); `path` is
    /// used in error messages and to resolve relative mesh paths.
    pub fn from_ron(text: &str, path: &Path) -> Result<Self, ConfigError> {
        // A UTF-8 byte-order mark (some editors save one) is not RON.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // `Designed(guidance: ..., weight: ...)` rather than `Designed((...))`.
        let options = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES);
        let mut scene: SceneConfig = options.from_str(text).map_err(|e| ConfigError::Parse {
            path: path.to_path_buf(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: messages::parse_message(text, &e, |t| options.from_str::<Self>(t).err()),
        })?;
        scene
            .validate()
            .map_err(|message| match locate_option(text, &message) {
                Some((line, column)) => ConfigError::InvalidAt {
                    path: path.to_path_buf(),
                    line,
                    column,
                    message,
                },
                None => ConfigError::Invalid {
                    path: path.to_path_buf(),
                    message,
                },
            })?;
        let base = path.parent().unwrap_or(Path::new("."));
        if let MeshSource::File(p) = &mut scene.mesh
            && p.is_relative()
        {
            *p = base.join(&*p);
        }
        scene.field.resolve_paths(base);
        Ok(scene)
    }

    /// The files this scene reads besides itself (its mesh file, its field files),
    /// absolute.
    pub fn input_files(&self) -> Vec<PathBuf> {
        let mesh = match &self.mesh {
            MeshSource::File(p) => Some(p.clone()),
            MeshSource::Shape(_) => None,
        };
        mesh.into_iter()
            .chain(self.field.files().into_iter().map(Path::to_path_buf))
            .filter_map(|p| std::path::absolute(&p).ok())
            .collect()
    }

    /// Reads and parses a scene file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_ron(&text, path)
    }

    /// The engine's preprocessing options of this scene: the `segment`, `param`,
    /// `curve` and `surface` sections. The one mapping from a scene to
    /// [`SurfaceOptions`]; every field of it comes from the scene.
    pub fn surface_options(&self) -> SurfaceOptions {
        // No `..Default::default()`: a new engine option must get a scene setting here.
        SurfaceOptions {
            segment: self.segment,
            param: self.param,
            curve: self.curve,
            min_segment_faces: self.surface.min_segment_faces,
            angle_criterion: self.surface.angle_criterion,
            isotropy_threshold: self.surface.isotropy_threshold,
            chart_angle: self.surface.chart_angle,
            merge_pieces: self.surface.merge_pieces,
        }
    }

    /// Checks value ranges that the types cannot express.
    pub fn validate(&self) -> Result<(), String> {
        crate::budget::check_count(self.sampling.count)
            .map_err(|e| format!("sampling option `count`: {e}"))?;
        self.field.validate().map_err(|e| e.to_string())?;
        // The parts one by one first, for messages that name the option alone.
        self.curve.validate().map_err(|e| e.to_string())?;
        self.segment.validate().map_err(|e| e.to_string())?;
        self.param.validate().map_err(|e| e.to_string())?;
        // Then what the engine checks of the options as a whole (`min_segment_faces`).
        self.surface_options()
            .validate()
            .map_err(|e| e.to_string())?;
        self.transform.validate()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimal_scene_takes_defaults() {
        let s = SceneConfig::from_ron(
            "(mesh: Shape(Plane(size: 2.0, resolution: 4)))",
            Path::new("x.ron"),
        )
        .expect("valid");
        assert_eq!(s.sampling, SamplingConfig::default());
        assert_eq!(s.curve, CurveOptions::default());
        assert_eq!(
            s.mesh,
            MeshSource::Shape(Shape::Plane {
                size: 2.0,
                resolution: 4
            })
        );
    }

    #[test]
    fn omitted_sections_give_the_engines_default_options() {
        let s = SceneConfig::from_ron("(mesh: Shape(Plane()))", Path::new("x.ron")).expect("valid");
        assert_eq!(s.surface_options(), SurfaceOptions::default());
        // Empty sections too.
        let s = SceneConfig::from_ron(
            "(mesh: Shape(Plane()), segment: (), param: (), curve: (), surface: ())",
            Path::new("x.ron"),
        )
        .expect("valid");
        assert_eq!(s.surface_options(), SurfaceOptions::default());
    }

    #[test]
    fn a_scene_sets_every_surface_option() {
        let text = r#"(
            mesh: Shape(Plane()),
            segment: (beta: 0.5, sigma: 2.0, seed: 11),
            param: (gamma: 0.25, isotropy_threshold: 1.5, max_stretch: 2.5),
            curve: (max_cell_share: 0.001, boundary_level: 9, max_level: 18, leaf_levels: 10),
            surface: (min_segment_faces: 5, angle_criterion: Max, isotropy_threshold: 1.3, chart_angle: 0.5, merge_pieces: false),
        )"#;
        let s = SceneConfig::from_ron(text, Path::new("all.ron")).expect("valid");
        let want = SurfaceOptions {
            segment: SegmentOptions {
                beta: 0.5,
                sigma: 2.0,
                seed: 11,
            },
            param: ParamOptions {
                gamma: 0.25,
                isotropy_threshold: 1.5,
                max_stretch: 2.5,
            },
            curve: CurveOptions {
                max_cell_share: 0.001,
                boundary_level: 9,
                max_level: 18,
                leaf_levels: 10,
            },
            min_segment_faces: 5,
            angle_criterion: AngleCriterion::Max,
            isotropy_threshold: 1.3,
            chart_angle: 0.5,
            merge_pieces: false,
        };
        assert_eq!(s.surface_options(), want);
        // Every value above differs from its default, so none was taken from there.
        let d = SurfaceOptions::default();
        assert!(d.segment.beta != 0.5 && d.segment.sigma != 2.0 && d.segment.seed != 11);
        assert!(d.param.gamma != 0.25 && d.param.isotropy_threshold != 1.5);
        assert!(d.param.max_stretch != 2.5 && d.chart_angle != 0.5 && d.merge_pieces);
        assert!(d.curve.max_cell_share != 0.001 && d.curve.boundary_level != 9);
        assert!(d.curve.max_level != 18 && d.curve.leaf_levels != 10);
        assert!(d.min_segment_faces != 5 && d.angle_criterion != AngleCriterion::Max);
        assert!(d.isotropy_threshold != 1.3);
        // The sections written back by serde parse to the same options (a field added
        // to one of them is covered by this round trip too).
        let text = format!(
            "(mesh: Shape(Plane()), segment: {}, param: {}, curve: {}, surface: {})",
            ron::to_string(&want.segment).expect("ron"),
            ron::to_string(&want.param).expect("ron"),
            ron::to_string(&want.curve).expect("ron"),
            ron::to_string(&s.surface).expect("ron"),
        );
        let again = SceneConfig::from_ron(&text, Path::new("again.ron")).expect("valid");
        assert_eq!(again.surface_options(), want);
    }

    #[test]
    fn bad_surface_settings_name_file_line_and_column() {
        let e = SceneConfig::from_ron(
            "(\n  mesh: Shape(Plane()),\n  surface: (min_segment_faces: 0),\n)",
            Path::new("s.ron"),
        )
        .expect_err("min_segment_faces 0");
        assert_eq!(
            e.to_string(),
            "s.ron:3:13: min_segment_faces must be at least 1"
        );
        let e = SceneConfig::from_ron(
            "(mesh: Shape(Plane()),\n surface: (angle_criterion: Median))",
            Path::new("s.ron"),
        )
        .expect_err("unknown criterion");
        assert!(e.to_string().starts_with("s.ron:2:"), "{e}");
        assert!(e.to_string().contains("Median"), "{e}");
        let e = SceneConfig::from_ron(
            "(mesh: Shape(Plane()), surface: (min_faces: 3))",
            Path::new("s.ron"),
        )
        .expect_err("unknown field");
        assert!(
            e.to_string().starts_with("s.ron:1:") && e.to_string().contains("min_faces"),
            "{e}"
        );
    }

    #[test]
    fn full_scene_parses() {
        let text = r#"(
            mesh: File("meshes/a.obj"),
            field: Constant(direction: (1.0, 1.0, 0.0), anisotropy: 4.0, density: 2.0),
            sampling: (count: 123, seed: 9),
            curve: (max_cell_share: 0.001, boundary_level: 8),
        )"#;
        let s = SceneConfig::from_ron(text, Path::new("/cfg/scene.ron")).expect("valid");
        assert_eq!(s.mesh, MeshSource::File(PathBuf::from("/cfg/meshes/a.obj")));
        assert_eq!(
            s.sampling,
            SamplingConfig {
                count: 123,
                seed: 9
            }
        );
        assert_eq!(s.curve.boundary_level, 8);
    }

    #[test]
    fn errors_have_file_line_and_column() {
        let text = "(\n  mesh: Shape(Plane(size: 1.0)),\n  sampling: (count: -4),\n)";
        let e = SceneConfig::from_ron(text, Path::new("bad.ron")).expect_err("negative count");
        let msg = e.to_string();
        assert!(msg.starts_with("bad.ron:3:"), "{msg}");
        // More samples than a request can index: refused at load, at the option.
        let text = "(\n  mesh: Shape(Plane(size: 1.0)),\n  sampling: (count: 4294967297),\n)";
        let e = SceneConfig::from_ron(text, Path::new("big.ron")).expect_err("2^32 + 1");
        assert_eq!(
            e.to_string(),
            "big.ron:3:14: sampling option `count`: at most 2^32 = 4294967296 samples per request (sample indices are 32-bit), asked for 4294967297"
        );
        let e = SceneConfig::from_ron("(mesh: Shape(Plane()), colour: 3)", Path::new("typo.ron"))
            .expect_err("unknown field");
        assert!(
            e.to_string().starts_with("typo.ron:1:") && e.to_string().contains("colour"),
            "{e}"
        );
        let e = SceneConfig::from_ron(
            "(mesh: Shape(Plane()), field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 0.5))",
            Path::new("range.ron"),
        )
        .expect_err("anisotropy < 1");
        assert!(e.to_string().contains("anisotropy"), "{e}");
        // Out-of-range values name the line and column of their option.
        let e = SceneConfig::from_ron(
            "(\n  mesh: Shape(Plane()),\n  curve: (boundary_level: 3, max_cell_share: 2.0),\n)",
            Path::new("range.ron"),
        )
        .expect_err("max_cell_share > 1");
        assert!(e.to_string().starts_with("range.ron:3:30: "), "{e}");
        let e = SceneConfig::from_ron(
            "(mesh: Shape(Plane()),\n transform: (scale: -1.0))",
            Path::new("t.ron"),
        )
        .expect_err("negative scale");
        assert!(e.to_string().starts_with("t.ron:2:14: "), "{e}");
        let e = SceneConfig::from_ron("(mesh: Shape(Plane(", Path::new("cut.ron"))
            .expect_err("truncated");
        assert!(e.to_string().starts_with("cut.ron:1:"), "{e}");
        let e = SceneConfig::load(Path::new("/nonexistent/scene.ron")).expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/scene.ron"), "{e}");
    }

    /// Issue 22: ron's "Expected comma" and raw-identifier hints become what the
    /// option expects and what was found.
    #[test]
    fn syntax_errors_say_what_was_expected_and_found() {
        let cases = [
            (
                "(mesh: Shape(Plane()), sampling: (count: 2000.5, seed: 1))",
                "x.ron:1:46: `count`: expected an integer, found `2000.5`",
            ),
            (
                "(mesh: Shape(Plane()), sampling: (count: -4))",
                "`count`: expected a non-negative integer, found `-4`",
            ),
            (
                "(mesh: Shape(Plane()), sampling: (count: many))",
                "`count`: expected an integer, found `many`",
            ),
            (
                "(mesh: Shape(Plane()),\n field: 3.0)",
                "x.ron:2:9: `field`: expected one of `Constant`, `Planar`, `Warp`, `File`, \
                 `Curvature`, `Designed` (a `FieldSpec`), found `3.0`",
            ),
            (
                "(mesh: Shape(Plane(size: x)))",
                "`size`: expected a number, found `x`",
            ),
        ];
        for (text, expected) in cases {
            let e = SceneConfig::from_ron(text, Path::new("x.ron")).expect_err(text);
            assert!(e.to_string().contains(expected), "{text}: {e}");
        }
    }
}
