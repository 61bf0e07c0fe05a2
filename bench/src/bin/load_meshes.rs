//! Mesh loading speed: `io::load` on every shared mesh and on the bunny Loop-subdivided
//! twice (1.1M faces) written as OBJ, ASCII PLY and binary PLY, as a Markdown table of
//! median MB/s: `cargo run --release -p strata-bench --bin load_meshes [-- repeats]`.
//!
//! Reads the meshes from `STRATA_MESH_DIR` or `../shared/meshes`. Each row is the median
//! of `repeats` loads (default 5) of the whole `io::load` (read, parse, `TriMesh`
//! construction with its repairs and adjacency); MB/s is the file's size over that
//! median (10^6 bytes). "build alone" is `TriMesh::new` on the loaded arrays, the part of
//! a load that is not the file format's. The generated files go to a temporary folder
//! (never stored): OBJ and ASCII PLY written here with 6 decimals, as scanners and
//! MeshLab write them; binary PLY by the project's own `io::write_mesh_ply` (f32).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use strata_bench::median;
use strata_engine::io;
use strata_engine::mesh::{TriMesh, loop_subdivide};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?;
    let dir = strata_bench::shared_mesh_dir()?;
    let mut files: Vec<PathBuf> = strata_bench::SHARED_MESHES
        .iter()
        .map(|name| dir.join(format!("{name}.obj")))
        .collect();

    let temp = tempfile::tempdir()?;
    let bunny = io::load(&dir.join("stanford-bunny.obj"))?;
    let big = loop_subdivide(&loop_subdivide(&bunny)?)?;
    let obj = temp.path().join("bunny-subdivided-2.obj");
    write_obj(&obj, &big)?;
    let ascii = temp.path().join("bunny-subdivided-2-ascii.ply");
    write_ascii_ply(&ascii, &big)?;
    let binary = temp.path().join("bunny-subdivided-2-binary.ply");
    io::write_mesh_ply(&binary, &big, None)?;
    files.extend([obj, ascii, binary]);

    println!("| file | MB | vertices | faces | load median (ms) | MB/s | build alone (ms) |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for path in &files {
        let bytes = std::fs::metadata(path)?.len() as f64;
        let mut times = Vec::with_capacity(repeats);
        let mut last = None;
        for _ in 0..repeats {
            let t = Instant::now();
            let mesh = io::load(path)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some(mesh);
        }
        let mesh = last.ok_or("no run")?;
        let load = median(times);
        let mut builds = Vec::with_capacity(repeats);
        for _ in 0..repeats {
            let (positions, triangles) = (mesh.positions().to_vec(), mesh.triangles().to_vec());
            let t = Instant::now();
            let built = TriMesh::new(positions, triangles)?;
            builds.push(t.elapsed().as_secs_f64());
            drop(built);
        }
        println!(
            "| {} | {:.1} | {} | {} | {:.1} | {:.0} | {:.1} |",
            path.file_name().unwrap_or_default().to_string_lossy(),
            bytes / 1e6,
            mesh.vertex_count(),
            mesh.face_count(),
            load * 1e3,
            bytes / 1e6 / load,
            median(builds) * 1e3,
        );
    }
    Ok(())
}

/// A plain OBJ: `v x y z` with 6 decimals, then `f a b c` (1-based).
fn write_obj(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let mut w = BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "# bunny, Loop-subdivided twice (strata load_meshes)")?;
    for p in mesh.positions() {
        writeln!(w, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
    }
    for t in mesh.triangles() {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    w.flush()
}

/// An ASCII PLY with `float x y z` (6 decimals) and `list uchar int vertex_indices`.
fn write_ascii_ply(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let mut w = BufWriter::new(std::fs::File::create(path)?);
    write!(
        w,
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertex_count(),
        mesh.face_count()
    )?;
    for p in mesh.positions() {
        writeln!(w, "{:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
    }
    for t in mesh.triangles() {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    w.flush()
}
