//! Test helper for the GPU modules: the layout naga gives a WGSL struct, which the
//! tests compare with the Rust twin's (`size_of`, `offset_of!`).
//!
//! Input: a WGSL module's source and a struct's name. Output: its members' byte
//! offsets and its size. Cost: one parse of the module.

/// Byte offsets of the members of WGSL struct `name` in module `source`, and its
/// size (naga's layout, which is what the GPU sees).
pub(super) fn wgsl_layout(source: &str, name: &str) -> (Vec<(String, usize)>, usize) {
    let module = naga::front::wgsl::parse_str(source).expect("WGSL module parses");
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("struct {name} in the module"));
    match &ty.inner {
        naga::TypeInner::Struct { members, span } => (
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
                .collect(),
            *span as usize,
        ),
        other => panic!("{name} is not a struct: {other:?}"),
    }
}
