//! The OBJ reader's parallel fast path against its sequential pass: the same scan
//! whenever the fast path gives one, and no scan exactly when the sequential pass
//! finds a problem or skips a face of one or two corners, whatever the chunk size.

use proptest::prelude::*;

use super::obj_fast::line;
use crate::io::obj::scan;
use crate::io::obj_chunks::scan_in_chunks;
use crate::io::shared_mesh_location;

/// Chunked scans of `text` at several chunk sizes agree with the sequential scan.
fn assert_agrees(text: &[u8]) {
    let sequential = scan(text);
    for size in [1, 7, 64, 4096] {
        match scan_in_chunks(text, size) {
            Some(fast) => {
                assert_eq!(
                    sequential.problem,
                    None,
                    "{:?}",
                    String::from_utf8_lossy(text)
                );
                assert_eq!(fast, sequential, "chunks of {size}");
            }
            None => assert!(
                sequential.problem.is_some() || sequential.skipped.count > 0,
                "chunks of {size} gave up on a valid file: {:?}",
                String::from_utf8_lossy(text)
            ),
        }
    }
}

#[test]
fn shared_meshes_scan_the_same_in_chunks() {
    let dir = shared_mesh_location();
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    let mut checked = 0;
    for entry in entries.flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "obj") {
            let bytes = std::fs::read(&path).expect("read");
            let sequential = scan(&bytes);
            assert_eq!(sequential.problem, None, "{}", path.display());
            for size in [4096, 1 << 16] {
                assert_eq!(scan_in_chunks(&bytes, size).as_ref(), Some(&sequential));
            }
            checked += 1;
        }
    }
    assert!(checked > 0, "no OBJ in {}", dir.display());
}

#[test]
fn relative_indices_and_late_records_cross_chunks() {
    // Negative indices that reach back over chunk boundaries, texture indices before
    // any texture coordinate (valid: the file has some later), and a byte-order mark.
    let text = "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\nv 0 0 1\nf -1 -2 -3\n\
                f -4 -3 -1\nvt 0 0\nf 1/-1 2/1 4/1\n";
    assert_agrees(text.as_bytes());
    // Out of range: a relative index reaching before the first vertex; a positive one
    // past the last; a texture index 0 when the file has texture coordinates; a
    // nameless material; a line that is not UTF-8.
    for bad in [
        "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n".as_bytes(),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/0 2/1 3/1\n",
        b"v 0 0 0\nusemtl \nv 1 0 0\n",
        b"v 0 0 0\nv 1 0 \xff\n",
    ] {
        assert!(scan(bad).problem.is_some());
        assert_agrees(bad);
    }
    // Texture indices (even 0 or out of range) are ignored when the file has none.
    assert_agrees(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/0 2/9 3/-4\n");
}

fn extra_line() -> impl Strategy<Value = String> {
    prop_oneof![
        20 => line(),
        1 => Just("usemtl".to_owned()),
        1 => Just("usemtl m".to_owned()),
        1 => Just("usemtl  ".to_owned()),
        1 => Just("f -1 -2 -3".to_owned()),
        1 => Just("f 1/-1 2/-2 3/1".to_owned()),
        1 => Just("vt 0.5 0.5".to_owned()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn random_files_scan_the_same_in_chunks(
        lines in prop::collection::vec(extra_line(), 0..32),
        crlf in any::<bool>(),
        header in any::<bool>(),
    ) {
        let newline = if crlf { "\r\n" } else { "\n" };
        let mut text = if header {
            ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 0 0 1"].join(newline) + newline
        } else {
            String::new()
        };
        text.push_str(&lines.join(newline));
        assert_agrees(text.as_bytes());
    }
}
