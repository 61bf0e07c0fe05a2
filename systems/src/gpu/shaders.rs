//! The WGSL sources, compiled into the binary from the workspace's `shaders/` folder.
//! Each pipeline's module is `common.wgsl` followed by the pipeline's file.

/// Shared structs (the twins of [`super::layout`]), uniforms and colour helpers.
pub const COMMON: &str = include_str!("../../../shaders/common.wgsl");

/// The splat pipeline's module: `common.wgsl` + `splat.wgsl`.
pub const SPLAT: &str = concat!(
    include_str!("../../../shaders/common.wgsl"),
    "\n",
    include_str!("../../../shaders/splat.wgsl")
);

/// The sample expansion pass's module: `common.wgsl` + `expand.wgsl`.
pub const EXPAND: &str = concat!(
    include_str!("../../../shaders/common.wgsl"),
    "\n",
    include_str!("../../../shaders/expand.wgsl")
);

/// The sampling passes' module: `sample.wgsl` + `progressive.wgsl` (they use nothing
/// of `common.wgsl`).
pub const SAMPLE: &str = concat!(
    include_str!("../../../shaders/sample.wgsl"),
    "\n",
    include_str!("../../../shaders/progressive.wgsl")
);

/// The mesh pipeline's module: `common.wgsl` + `mesh.wgsl`.
pub const MESH: &str = concat!(
    include_str!("../../../shaders/common.wgsl"),
    "\n",
    include_str!("../../../shaders/mesh.wgsl")
);

/// The stroke and stipple pipelines' module: `common.wgsl` + `npr.wgsl`.
pub const NPR: &str = concat!(
    include_str!("../../../shaders/common.wgsl"),
    "\n",
    include_str!("../../../shaders/npr.wgsl")
);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every module parses and validates with naga (the checks wgpu runs at pipeline
    /// creation), with the capabilities of a downlevel device.
    #[test]
    fn every_wgsl_module_validates() {
        for (name, source, entry_points) in [
            ("common", COMMON, &[][..]),
            (
                "splat",
                SPLAT,
                &["vs_splat", "fs_disc", "fs_gaussian", "vs_glyph", "fs_glyph"][..],
            ),
            ("mesh", MESH, &["vs_mesh", "fs_mesh"][..]),
            ("expand", EXPAND, &["cs_expand"][..]),
            ("sample", SAMPLE, &["cs_sample", "cs_progressive"][..]),
            (
                "npr",
                NPR,
                &[
                    "vs_paper",
                    "fs_paper",
                    "vs_depth",
                    "fs_depth",
                    "vs_stroke",
                    "fs_stroke",
                    "vs_stipple",
                    "fs_stipple",
                ][..],
            ),
        ] {
            let module = naga::front::wgsl::parse_str(source)
                .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
            for entry in entry_points {
                assert!(
                    module.entry_points.iter().any(|e| e.name == *entry),
                    "{name}: entry point {entry}"
                );
            }
        }
    }
}
