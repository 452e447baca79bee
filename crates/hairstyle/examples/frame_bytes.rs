//! Bytes the viewer needs per visual frame, and once at connect, for hairstyles of 10,000 and
//! 150,000 render strands, following the FRAME and SCENE layouts of the WebSocket viewer protocol
//! (docs/protocol.md on the `web` branch; `crates/server/src/protocol.rs` there). Sizes are
//! computed from the hairstyle's real counts (lattice nodes, guides, samples, head mesh).
//! Run: `cargo run --release -p coiffure-hairstyle --example frame_bytes`.

use hairstyle::{Hairstyle, HairstyleParams};
use lattice::lattice::{CarryParams, LatticeParams};

/// FRAME payload bytes: 2-byte header, u32 sequence, f32 time, u8 tool, u8 flags, u16 contacts,
/// proxy 3 f32, quaternion 4 f32, device 3 f32, force 3 f32, u32 lattice version, u32 N + N x 3
/// f32 nodes, u32 A + u32 K + A u32 + A x K x 3 f32 guide displacements, u32 G + G f32 wetness +
/// G f32 kept length.
fn frame_bytes(nodes: usize, active: usize, samples: usize, guides: usize) -> usize {
    2 + 4 + 4 + 1 + 1 + 2 + 12 + 16 + 12 + 12 + 4
        + 4 + 12 * nodes
        + 4 + 4 + 4 * active + 12 * active * samples
        + 4 + 4 * guides + 4 * guides
}

/// SCENE payload bytes: header, 8 u32 counts, origin and cell, hair-type names, padding, head
/// mesh, render rest positions, guide indices and weights, spans.
fn scene_bytes(h: &Hairstyle, mesh_vertices: usize, mesh_indices: usize) -> usize {
    let names: usize = strand::HairType::ALL.iter().map(|t| 1 + t.name.len()).sum();
    let mut n = 2 + 8 * 4 + 16 + 1 + names + 1;
    n = n.div_ceil(4) * 4;
    let r = &h.render;
    let (s, p) = (r.len(), r.guides_per_strand);
    n + 8 + 12 * mesh_vertices + 4 * mesh_indices + 12 * r.positions.len() + 8 * s * p + 4 * s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "{:>8} {:>6} {:>7} {:>7} {:>12} {:>12} {:>12} {:>14}",
        "strands", "guides", "samples", "nodes", "frame A=0", "frame A=20", "frame 60 Hz", "scene (once)"
    );
    for render in [10_000usize, 150_000] {
        let h = Hairstyle::generate(&HairstyleParams {
            render_count: render,
            ..Default::default()
        })?;
        let hl = h.lattice(&CarryParams::default(), LatticeParams::default())?;
        let nodes = hl.model.node_count();
        let mesh = h.head.mesh();
        let (g, k) = (h.guides.len(), h.render.guide_samples);
        let f0 = frame_bytes(nodes, 0, k, g);
        let f20 = frame_bytes(nodes, 20.min(g), k, g);
        let scene = scene_bytes(&h, mesh.positions.len(), mesh.indices.len());
        println!(
            "{:>8} {:>6} {:>7} {:>7} {:>12} {:>12} {:>9.2} MB/s {:>11.1} MB",
            h.render.len(),
            g,
            k,
            nodes,
            f0,
            f20,
            60.0 * f20 as f64 / 1e6,
            scene as f64 / 1e6
        );
    }
    println!("frame: 12 B per lattice node + 12 K B per active guide + 8 B per guide + 90 B; no render strand term");
    Ok(())
}
