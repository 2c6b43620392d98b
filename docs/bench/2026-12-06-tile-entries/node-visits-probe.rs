//! A record, not compiled: the probe that counted the node visits a tile's entry node
//! saves. It ran as `src/bvh/frustum_probe.rs` (`mod frustum_probe;` in src/bvh/mod.rs) at
//! 5b4ff34: `cargo test --release --lib frustum_entry_probe -- --nocapture`, with
//! SIMPLE=1 for the walk cltrace keeps (stop where two children may meet the tile's
//! frustum) and BOUND=k for a bounded search below such nodes; without SIMPLE, the exact
//! lowest common ancestor of the leaves meeting the frustum.
#![cfg(test)]
use super::*;
use crate::camera::Camera;
use crate::intersect::RayBox;
use glam::Vec3;
use std::path::Path;

fn visits(b: &Bin32Bvh, ray: &crate::geometry::Ray, lo: usize, hi: usize) -> (u32, u32) {
    // Aila-Laine counting on bin32: an inner-node iteration = one bin64 node fetch.
    let tri_ray = crate::intersect::WatertightRay::new(ray);
    let box_ray = RayBox::new(ray);
    let mut t = f32::INFINITY;
    let mut stack = vec![];
    let (mut all, mut inside) = (0u32, 0u32);
    if b.nodes[0].hit(&box_ray, t).is_none() { return (0, 0); }
    let mut node = 0usize;
    loop {
        let n = &b.nodes[node];
        if n.is_leaf() {
            let first = n.left_or_first as usize;
            for i in first..first + n.count() as usize {
                if let Some(h) = tri_ray.intersect_stored(&b.triangles[i], t) { t = h; }
            }
        } else {
            all += 1;
            if node >= lo && node < hi { inside += 1; }
            let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
            match (b.nodes[l].hit(&box_ray, t), b.nodes[r].hit(&box_ray, t)) {
                (Some(tl), Some(tr)) => {
                    let (near, far) = if tr < tl { (r, l) } else { (l, r) };
                    stack.push(far); node = near; continue;
                }
                (Some(_), None) => { node = l; continue; }
                (None, Some(_)) => { node = r; continue; }
                _ => {}
            }
        }
        match stack.pop() { Some(n) => node = n, None => break }
    }
    (all, inside)
}

#[test]
fn frustum_entry_probe() {
    for name in ["stanford_bunny.obj", "stanford_dragon.obj.gz"] {
        let path = format!("../shared/scenes/{name}");
        let mesh = crate::input::load_mesh(Path::new(&path)).unwrap();
        let (w, h) = (1920u32, 1080u32);
        let cam = Camera::bench(&mesh.bounds(), w, h).unwrap();
        let pin = cam.pinhole();
        let b = Bin32Bvh::new(Bvh::build(&mesh, &BuildOptions::default()), &mesh);
        // subtree end of each node (depth-first).
        let mut end = vec![0usize; b.nodes.len()];
        for i in (0..b.nodes.len()).rev() {
            let n = &b.nodes[i];
            end[i] = if n.is_leaf() { i + 1 } else { end[n.right_or_count as usize] };
        }
        let eye = Vec3::from_slice(&pin.eye[..3]);
        for tile in [(8u32, 8u32), (16, 16), (32, 32)] {
            let (mut all, mut inside, mut depth_sum, mut tiles) = (0u64, 0u64, 0u64, 0u64);
            let (mut hit_all, mut hit_in, mut hit_n, mut warp_all, mut warp_in) = (0u64, 0u64, 0u64, 0u64, 0u64);
            for ty in (0..h).step_by(tile.1 as usize) {
                for tx in (0..w).step_by(tile.0 as usize) {
                    let x1 = (tx + tile.0).min(w) as f32; let y1 = (ty + tile.1).min(h) as f32;
                    let m = 0.01f32;
                    let c = [
                        pin.ray_at(tx as f32 + 0.5 - m, ty as f32 + 0.5 - m).dir,
                        pin.ray_at(x1 - 0.5 + m, ty as f32 + 0.5 - m).dir,
                        pin.ray_at(x1 - 0.5 + m, y1 - 0.5 + m).dir,
                        pin.ray_at(tx as f32 + 0.5 - m, y1 - 0.5 + m).dir,
                    ];
                    // inward normals of the 4 side planes
                    let mid = (c[0] + c[1] + c[2] + c[3]) * 0.25;
                    let planes: Vec<Vec3> = (0..4).map(|k| {
                        let nrm = c[k].cross(c[(k + 1) % 4]);
                        if nrm.dot(mid) < 0.0 { -nrm } else { nrm }
                    }).collect();
                    let passes = |n: &Bin32Node| {
                        let (mn, mx) = (Vec3::from(n.min) - eye, Vec3::from(n.max) - eye);
                        planes.iter().all(|p| {
                            let v = Vec3::new(if p.x > 0.0 { mx.x } else { mn.x }, if p.y > 0.0 { mx.y } else { mn.y }, if p.z > 0.0 { mx.z } else { mn.z });
                            p.dot(v) >= -1e-6 * p.length() * v.length()
                        })
                    };
                    // collect passing leaves
                    let mut leaves = vec![];
                    let mut st = vec![0usize];
                    while let Some(i) = st.pop() {
                        let n = &b.nodes[i];
                        if !passes(n) { continue; }
                        if n.is_leaf() { leaves.push(i); } else { st.push(n.left_or_first as usize); st.push(n.right_or_count as usize); }
                    }
                    let simple = std::env::var("SIMPLE").is_ok();
                    let (lo, hi, d) = if simple {
                        let mut e = 0usize; let mut d = 0; let mut none = !passes(&b.nodes[0]);
                        while !none && !b.nodes[e].is_leaf() {
                            let n = &b.nodes[e];
                            let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
                            match (passes(&b.nodes[l]), passes(&b.nodes[r])) {
                                (true, true) => {
                                    // bounded search: does a child hold any passing leaf?
                                    let k: usize = std::env::var("BOUND").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
                                    let any = |c: usize| -> Option<bool> {
                                        let mut st = vec![c]; let mut tests = 0;
                                        while let Some(i) = st.pop() {
                                            let n = &b.nodes[i];
                                            if n.is_leaf() { return Some(true); }
                                            for ch in [n.right_or_count as usize, n.left_or_first as usize] {
                                                tests += 1;
                                                if passes(&b.nodes[ch]) { st.push(ch); }
                                            }
                                            if tests > k { return None; }
                                        }
                                        Some(false)
                                    };
                                    if k == 0 { break; }
                                    match (any(l), any(r)) {
                                        (Some(false), _) => e = r,
                                        (_, Some(false)) => e = l,
                                        _ => break,
                                    }
                                }
                                (true, false) => e = l,
                                (false, true) => e = r,
                                _ => { none = true; }
                            }
                            d += 1;
                        }
                        if none { (0, 0, 0) } else { (e, end[e], d) }
                    } else if leaves.is_empty() { (0, 0, 0) } else {
                        let (mn, mx) = (*leaves.iter().min().unwrap(), *leaves.iter().max().unwrap());
                        let mut e = 0usize; let mut d = 0;
                        loop {
                            let n = &b.nodes[e];
                            if n.is_leaf() { break; }
                            let (l, r) = (n.left_or_first as usize, n.right_or_count as usize);
                            if mn >= l && mx < end[l] { e = l; } else if mn >= r && mx < end[r] { e = r; } else { break; }
                            d += 1;
                        }
                        (e, end[e], d)
                    };
                    if !leaves.is_empty() { depth_sum += d; tiles += 1; }
                    for wy in (ty..(ty + tile.1).min(h)).step_by(4) {
                        let (mut ma, mut mi) = (0u32, 0u32);
                        for y in wy..(wy + 4).min(h) { for x in tx..(tx + tile.0).min(w) {
                            let (a, i) = visits(&b, &pin.ray(x, y), lo, hi);
                            all += a as u64; inside += i as u64;
                            if a > 2 { hit_all += a as u64; hit_in += i as u64; hit_n += 1; }
                            ma = ma.max(a); mi = mi.max(i);
                        }}
                        warp_all += ma as u64; warp_in += mi as u64;
                    }
                }
            }
            println!("{name} tile {:?}: visits/ray {:.2}, from entry {:.2} ({:.1}% saved), mean entry depth {:.1} over {} tiles",
                tile, all as f64 / (w * h) as f64, inside as f64 / (w * h) as f64, 100.0 * (1.0 - inside as f64 / all as f64), depth_sum as f64 / tiles as f64, tiles);
            println!("   rays with >2 visits: {} of them, {:.2} -> {:.2} ({:.1}% saved); warp max sum {} -> {} ({:.1}% saved)", hit_n, hit_all as f64 / hit_n as f64, hit_in as f64 / hit_n as f64, 100.0 * (1.0 - hit_in as f64 / hit_all as f64), warp_all, warp_in, 100.0 * (1.0 - warp_in as f64 / warp_all as f64));
        }
    }
}
