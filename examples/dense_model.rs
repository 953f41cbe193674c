//! Writes a dense character as `.glb`, for measuring the bake on large models (a scanned or
//! sculpted character): the armour test model (a knight of many parts, rivets and seams, one
//! walk clip) with its shapes' segments multiplied until it has at least the triangles asked:
//!
//! `cargo run --release --example dense_model -- 2000000 dense.glb`, then
//! `/usr/bin/time -v target/release/lodlab bake dense.glb`.

use anyhow::{Context, Result, bail};
use lodlab::generate::armour::armour_at;
use lodlab::generate::glb::to_glb;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [triangles, out] = args.as_slice() else {
        bail!("usage: dense_model TRIANGLES OUT.glb");
    };
    let want: usize = triangles.parse().context("TRIANGLES: a whole number")?;
    // Triangles grow with the square of the detail: start from the test model's count and
    // step up until there are enough.
    let at_one = armour_at(1.0).mesh.triangle_count();
    let mut detail = (want as f32 / at_one as f32).sqrt().max(1.0);
    let mut model = armour_at(detail);
    while model.mesh.triangle_count() < want {
        detail *= 1.02;
        model = armour_at(detail);
    }
    model.name = "dense".into();
    lodlab::atomic::write(std::path::Path::new(out), &to_glb(&model))?;
    println!(
        "{out}: {} triangles, {} vertices (detail {detail:.2})",
        model.mesh.triangle_count(),
        model.mesh.vertex_count()
    );
    Ok(())
}
