// The axes of the top four levels of splits of main's BVH (default build), for the guess in
// ../2026-12-06-tinybvh.md: a binary crate outside the project with cltrace as a path
// dependency; `probe MESH...` prints, per level, how many inner nodes split along x, y, z.
use cltrace::bvh::{Bvh, BuildOptions};
use std::path::Path;
fn main() {
    for p in std::env::args().skip(1) {
        let mesh = cltrace::input::load_mesh(Path::new(&p)).unwrap();
        let bvh = Bvh::build(&mesh, &BuildOptions::default());
        let n = &bvh.nodes;
        println!("{p}: {} nodes", n.len());
        // Breadth-first over the top 4 levels: the axis along which the children's centres differ most.
        let mut level = vec![0usize];
        for depth in 0..4 {
            let mut next = vec![];
            let mut axes = [0; 3];
            for &i in &level {
                if n[i].is_leaf() { continue; }
                let (l, r) = (i + 1, n[i].right_or_count as usize);
                let c = |k: usize| [0, 1, 2].map(|a| (n[k].min[a] + n[k].max[a]) * 0.5);
                let (cl, cr) = (c(l), c(r));
                let d = [0, 1, 2].map(|a| (cl[a] - cr[a]).abs());
                let axis = (0..3).max_by(|&a, &b| d[a].partial_cmp(&d[b]).unwrap()).unwrap();
                axes[axis] += 1;
                next.push(l); next.push(r);
            }
            println!("  depth {depth}: split axes x {} y {} z {}", axes[0], axes[1], axes[2]);
            level = next;
        }
    }
}
