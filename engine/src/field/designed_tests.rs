//! Tests of the designed field source: settings, constraints, the tensor it builds.

use glam::DVec3;

use super::*;
use crate::mesh::shapes;

#[test]
fn placeholder_builds() {
    let mesh = shapes::sphere(1.0, 4).expect("sphere");
    let field = Design::default().build(&mesh).expect("field");
    assert_eq!(field.tensors().len(), mesh.vertex_count());
    let _ = DVec3::ZERO;
}
