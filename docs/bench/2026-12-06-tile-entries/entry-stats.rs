//! A record, not compiled: counts where the tiles of the bench's 1080p camera start, per
//! layout (PoCL), through `ClTracer::tile_entries`; built as a crate depending on cltrace
//! at 94ca448 and run on stanford_bunny.obj and stanford_dragon.obj.gz.
use cltrace::bvh::{Bin32Bvh, BuildOptions, Bvh, DeviceLayout, Layout};
use cltrace::camera::Camera;
use cltrace::device::{ClDevice, ClTracer, Kernels};
use cltrace::device::DeviceSelector;
use std::path::Path;
fn main() {
    let dev = ClDevice::select(&DeviceSelector::Name("Portable".into())).unwrap();
    for m in std::env::args().skip(1) {
        let mesh = cltrace::input::load_mesh(Path::new(&m)).unwrap();
        let cam = Camera::bench(&mesh.bounds(), 1920, 1080).unwrap();
        for layout in Layout::ALL {
            let bvh = Bvh::build(&mesh, &BuildOptions::default());
            let sah = bvh.stats().sah_cost;
            let laid = DeviceLayout::new(Bin32Bvh::new(bvh, &mesh), layout, sah);
            let prog = ClTracer::compile(&dev, Some((layout, laid.stack_size)), Kernels::PRIMARY).unwrap();
            let mut t = ClTracer::with_layout(&dev, &prog, &laid).unwrap();
            let e = t.tile_entries(&cam.pinhole(), 1920, 1080).unwrap().unwrap();
            let miss = e.iter().filter(|&&x| x == u32::MAX).count();
            let root = e.iter().filter(|&&x| x == 0).count();
            println!("{m} {}: {} tiles, {} empty, {} at the root, {} below", layout.name(), e.len(), miss, root, e.len() - miss - root);
        }
    }
}
