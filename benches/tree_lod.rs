//! Frame times of a forest of 100 trees drawn at each level of their billboard-cloud chain, as
//! ratios measured in one run: `cargo bench --bench tree_lod` (on lavapipe, or whatever
//! adapter wgpu picks). Also the wall time of building each chain (clouds and atlases), and
//! the ratios net of the frame without trees (sky, ground: the same at every level).

use anyhow::{Result, anyhow};
use lodlab::bake::foliage::billboard::chain::{ChainOptions, CloudLevel, tree_chain};
use lodlab::bake::foliage::billboard::foliage;
use lodlab::render::Gpu;
use lodlab::render::atlas::AtlasRasterizer;
use lodlab::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use lodlab::runtime::headless::time_renderer;
use lodlab::runtime::spec::Loaded;
use lodlab::runtime::world::World;

const TREES: usize = 100;
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 720;

fn main() -> Result<()> {
    let gpu = Gpu::headless()?;
    println!("adapter: {}", gpu.describe());
    for name in ["broadleaf", "conifer"] {
        let tree = lodlab::import::load_model(name)?;
        let f = foliage(&tree).map_err(|e| anyhow!(e))?;
        let start = std::time::Instant::now();
        let chain = tree_chain(
            &AtlasRasterizer::new(&gpu),
            &tree,
            &f,
            &ChainOptions::default(),
            &|_| {},
        )?;
        println!(
            "\n{name}: chain of {} levels built in {:.2} s; {TREES} trees, {WIDTH}x{HEIGHT}",
            chain.len(),
            start.elapsed().as_secs_f64()
        );
        println!(
            "{:<5} {:>10} {:>10} {:>10} {:>6} {:>6} {:>10} {:>6} {:>6}",
            "level",
            "billboards",
            "triangles",
            "ms MSAA 4",
            "vs L0",
            "net",
            "ms 1x",
            "vs L0",
            "net"
        );
        let time = |l: &CloudLevel, count: usize, samples: u32| -> Result<(f64, u64)> {
            let mut loaded = Loaded::forest_of(&l.model, l.motion.as_ref(), TREES)?;
            loaded.spec.count = count;
            let mut world = World::new(&gpu, loaded, OFFSCREEN_FORMAT, samples)?;
            let target = Offscreen::new(&gpu, WIDTH, HEIGHT, samples);
            let triangles = world.prepare(&gpu, [WIDTH, HEIGHT], 2.0, 0.0).triangles;
            time_renderer(&gpu, &world.renderer, &target, 1, None)?;
            Ok((
                time_renderer(&gpu, &world.renderer, &target, 7, None)?.0,
                triangles,
            ))
        };
        let empty = [
            time(&chain[0].cloud, 0, 4)?.0,
            time(&chain[0].cloud, 0, 1)?.0,
        ];
        println!("no trees: {:.1} ms MSAA 4, {:.1} ms 1x", empty[0], empty[1]);
        let mut l0 = [0.0; 2];
        for (k, level) in chain.iter().enumerate() {
            let mut ms = [0.0; 2];
            let mut triangles = 0;
            for (i, samples) in [4, 1].into_iter().enumerate() {
                (ms[i], triangles) = time(&level.cloud, TREES, samples)?;
                if k == 0 {
                    l0[i] = ms[i];
                }
            }
            let net = |i: usize| (l0[i] - empty[i]) / (ms[i] - empty[i]).max(1e-3);
            println!(
                "L{k:<4} {:>10} {:>10} {:>10.1} {:>5.1}x {:>5.1}x {:>10.1} {:>5.1}x {:>5.1}x",
                level.cloud.billboards,
                triangles,
                ms[0],
                l0[0] / ms[0],
                net(0),
                ms[1],
                l0[1] / ms[1],
                net(1)
            );
        }
    }
    Ok(())
}
