//! `lodlab bake` and `lodlab report` as a user runs them, and the on-disk cache behind them.

use lodlab::bake::cache::{LodCache, Origin};
use lodlab::bake::character::lod::LodOptions;
use lodlab::bake::character::lod::cached::{levels_key, levels_path, load_or_bake};
use lodlab::bake::character::simplify::Method;
use lodlab::generate::cylinder::bent_cylinder;
use lodlab::generate::glb::to_glb;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lodlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodlab"))
        .args(args)
        .output()
        .expect("lodlab runs")
}

fn cylinder_glb(dir: &Path) -> PathBuf {
    let p = dir.join("cylinder.glb");
    std::fs::write(&p, to_glb(&bent_cylinder(12, 10))).unwrap();
    p
}

fn options() -> LodOptions {
    LodOptions {
        base_error: 1e-3,
        floor_triangles: 20,
        budgets: None,
    }
}

#[test]
fn cache_hits_and_rebuilds_what_it_cannot_trust() {
    let dir = tempfile::tempdir().unwrap();
    let cache = LodCache::new(Some(dir.path().join("cache")));
    let model = bent_cylinder(8, 8);
    let source = [7u8; 32];
    let (first, origin) = load_or_bake(
        &cache,
        &model,
        &source,
        Method::AnimationSpace,
        &options(),
        &|_| {},
    );
    assert_eq!(origin, Origin::Baked { warning: None });
    let (again, origin) = load_or_bake(
        &cache,
        &model,
        &source,
        Method::AnimationSpace,
        &options(),
        &|_| {},
    );
    assert_eq!(origin, Origin::Cache);
    assert_eq!(again, first);

    let path = levels_path(
        &cache,
        &model.name,
        Method::AnimationSpace,
        &levels_key(&source, Method::AnimationSpace, &options()),
    );
    let good = std::fs::read(&path).unwrap();
    let damaged: Vec<(&str, Vec<u8>)> = vec![
        ("corrupt", {
            let mut b = good.clone();
            let last = b.len() - 10;
            b[last] ^= 0x55;
            b
        }),
        ("truncated", good[..good.len() / 2].to_vec()),
        ("cache format", {
            let mut b = good.clone();
            b[8] = b[8].wrapping_add(1);
            b
        }),
        ("not a lodlab cache file", b"hello".to_vec()),
    ];
    for (why, bytes) in damaged {
        std::fs::write(&path, &bytes).unwrap();
        let (lods, origin) = load_or_bake(
            &cache,
            &model,
            &source,
            Method::AnimationSpace,
            &options(),
            &|_| {},
        );
        match origin {
            Origin::Baked { warning: Some(w) } => {
                assert!(w.contains(why), "expected '{why}' in: {w}");
                assert!(w.contains(&path.display().to_string()), "{w}");
                assert!(!w.contains('\n'));
            }
            other => panic!("{why}: {other:?}"),
        }
        assert_eq!(lods.levels, first.levels);
        // Rebuilt and rewritten: the next lookup hits.
        let (_, origin) = load_or_bake(
            &cache,
            &model,
            &source,
            Method::AnimationSpace,
            &options(),
            &|_| {},
        );
        assert_eq!(origin, Origin::Cache, "{why}");
    }
    // Other parameters, another source or another method: another file.
    let mut other = options();
    other.base_error *= 2.0;
    assert_ne!(
        levels_key(&source, Method::AnimationSpace, &options()),
        levels_key(&source, Method::AnimationSpace, &other)
    );
    assert_ne!(
        levels_key(&source, Method::AnimationSpace, &options()),
        levels_key(&[8u8; 32], Method::AnimationSpace, &options())
    );
    assert_ne!(
        levels_key(&source, Method::AnimationSpace, &options()),
        levels_key(&source, Method::RestPose, &options())
    );
}

#[test]
fn source_hash_follows_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = cylinder_glb(dir.path());
    let source_hash = |p: &std::path::Path| {
        lodlab::import::import(p.to_str().unwrap(), &Default::default())
            .unwrap()
            .source_hash
    };
    let a = source_hash(&p);
    assert_eq!(a, source_hash(&p));
    std::fs::write(&p, to_glb(&bent_cylinder(12, 11))).unwrap();
    assert_ne!(a, source_hash(&p));
}

#[test]
fn bake_prints_levels_and_uses_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let model = cylinder_glb(dir.path());
    let cache = dir.path().join("cache");
    let args = [
        "bake",
        model.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ];
    let out = lodlab(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout);
    for method in ["rest-pose", "as", "as+is"] {
        assert!(
            table
                .lines()
                .any(|l| l.starts_with(&format!("{method:<10}   1"))),
            "no LOD 1 row for {method}:\n{table}"
        );
    }
    assert!(table.contains("240 triangles"), "{table}");
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 3);
    let again = lodlab(&args);
    assert!(again.status.success());
    let table2 = String::from_utf8_lossy(&again.stdout);
    assert_eq!(table2.matches("cached").count(), 3, "{table2}");

    // One method, budgets instead of errors.
    let out = lodlab(&[
        "bake",
        model.to_str().unwrap(),
        "--methods",
        "as+is",
        "--triangles",
        "120,60",
        "--cache",
        cache.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    // 60 is under what a level may go down to: said, with the floor.
    let err = String::from_utf8_lossy(&out.stderr);
    let warning = err.lines().find(|l| l.starts_with("warning:")).expect(&err);
    assert!(
        warning.contains("cylinder (as+is)") && warning.contains("budget 60 below its floor of"),
        "{warning}"
    );
    let t = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        t.lines().filter(|l| l.starts_with("as+is")).count(),
        3,
        "{t}"
    );
}

#[test]
fn bake_and_report_reject_bad_input_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.glb");
    for args in [
        vec!["bake", missing.to_str().unwrap()],
        vec!["report", missing.to_str().unwrap(), "--out", "/tmp"],
    ] {
        let out = lodlab(&args);
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains("missing.glb"), "{err}");
    }
    // A model without texture coordinates bakes, flattening each neighbourhood instead.
    let mut flat = bent_cylinder(6, 6);
    flat.mesh.uvs.iter_mut().for_each(|u| *u = glam::Vec2::ZERO);
    let p = dir.path().join("no-uv.glb");
    std::fs::write(&p, to_glb(&flat)).unwrap();
    let out = lodlab(&[
        "bake",
        "--model",
        p.to_str().unwrap(),
        "--cache",
        dir.path().join("c").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The output folder is a file.
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"mine").unwrap();
    let model = cylinder_glb(dir.path());
    let out = lodlab(&[
        "report",
        model.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read(&file).unwrap(), b"mine");
    // An unknown method is a usage error.
    let out = lodlab(&["bake", "horse", "--methods", "fast"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn report_writes_curves_plot_and_timings() {
    let dir = tempfile::tempdir().unwrap();
    let model = cylinder_glb(dir.path());
    let out_dir = dir.path().join("report");
    let cache = dir.path().join("cache");
    let out = lodlab(&[
        "report",
        model.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--baseline",
        "meshopt",
        "--cache",
        cache.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("read from the cache"), "{stderr}");
    // The report baked the three methods' levels into the cache, where the viewer, `bake`
    // and a second report find them (as `bake` says).
    let bake = lodlab(&[
        "bake",
        model.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--json",
    ]);
    assert!(bake.status.success());
    let baked: serde_json::Value = serde_json::from_slice(&bake.stdout).unwrap();
    // A bake from the cache has no bake time.
    let from_cache: Vec<bool> = baked["characters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["bake_seconds"].is_null())
        .collect();
    assert_eq!(from_cache, [true; 3], "{baked}");
    // Its findings a line each, none of them a paragraph.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.lines().count() >= 5, "{stdout}");
    assert!(stdout.lines().all(|l| l.chars().count() <= 160), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["model"], "cylinder");
    assert_eq!(json["triangles"], 240);
    assert_eq!(json["bones"], 2);
    for method in ["rest-pose", "as", "as+is", "meshopt"] {
        let m = &json["methods"][method];
        assert!(m["bake_seconds"].as_f64().unwrap() >= 0.0, "{method}");
        let curve = m["curve"].as_array().unwrap();
        assert!(curve.len() >= 30, "{method}: {} points", curve.len());
        assert_eq!(curve[0]["triangles"], 240, "{method} starts at full detail");
        assert!(curve[0]["rms_error"].as_f64().unwrap() < 1e-9);
        let last = curve.last().unwrap();
        assert!(last["rms_error"].as_f64().unwrap() > 0.0);
        assert!(last["max_error"].as_f64().unwrap() >= last["rms_error"].as_f64().unwrap());
        // Coarser along the curve.
        for w in curve.windows(2) {
            assert!(w[1]["influences"].as_u64() <= w[0]["influences"].as_u64());
        }
    }
    assert!(json["methods"]["as+is"]["cache_hit_rate"].as_f64().unwrap() > 0.0);
    // Every method in 5 tie orders: each point the median with its band, every order
    // counted where it reaches.
    assert_eq!(json["orders"], 5);
    for method in ["rest-pose", "as", "as+is", "meshopt"] {
        for p in json["methods"][method]["curve"].as_array().unwrap() {
            let v = |k: &str| p[k].as_f64().unwrap();
            assert!(
                v("rms_low") <= v("rms_error") && v("rms_error") <= v("rms_high"),
                "{method}: {p}"
            );
            assert!((1..=5).contains(&p["orders"].as_u64().unwrap()), "{p}");
        }
        assert!(json["methods"][method]["band"].as_f64().unwrap() >= 0.0);
    }
    // The methods compared where their bands separate, and where that is.
    let c = &json["comparison"];
    let fraction = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k}: {c}"));
    for pair in ["as vs rest-pose", "as+is vs as", "meshopt vs rest-pose"] {
        let s = &c["separations"][pair];
        let share = |k: &str| s[k].as_f64().unwrap();
        let total = share("better") + share("indistinguishable") + share("worse");
        assert!((total - 1.0).abs() < 1e-4, "{pair}: {s}");
        assert!(!s["spans"].as_array().unwrap().is_empty(), "{pair}: {s}");
        assert!(s["says"].as_str().unwrap().contains(" influences"), "{s}");
    }
    assert!(fraction("as_over_rest_pose") > 0.0);
    // A share of the points where the bands separate; null where they never do.
    let at_levels = &c["as_le_rest_pose_at_levels"];
    assert!(
        at_levels.is_null() || (0.0..=1.0).contains(&at_levels.as_f64().unwrap()),
        "{at_levels}"
    );
    // The lighting of AS+IS against AS's at equal influences: a ratio where the levels
    // show any colour error, else null.
    let lighting = &c["as_is_lighting_over_as"];
    assert!(
        lighting.is_null() || lighting.as_f64().unwrap() >= 0.0,
        "{lighting}"
    );
    // Every level but full detail's lighting, by vertex normals and through its map,
    // meshoptimizer's levels' too.
    for method in ["rest-pose", "as", "as+is", "meshopt"] {
        let m = &json["methods"][method];
        let shading = m["shading"].as_array().unwrap();
        assert_eq!(
            shading.len(),
            m["levels"].as_array().unwrap().len() - 1,
            "{method}"
        );
        for s in shading {
            assert!(s["vertex_normals"].as_f64().unwrap() >= 0.0);
            assert!(s["normal_maps"].as_f64().unwrap() >= 0.0);
        }
    }
    // meshoptimizer's levels as the viewer bakes them, and where they end, said.
    let meshopt_levels = json["methods"]["meshopt"]["levels"].as_array().unwrap();
    assert!(meshopt_levels.len() >= 2, "{meshopt_levels:?}");
    assert!(
        stdout.contains("meshopt's levels stop short at")
            || stdout.contains("meshopt's levels reach"),
        "{stdout}"
    );
    let timings = std::fs::read_to_string(out_dir.join("timings.md")).unwrap();
    assert!(timings.contains("## Lighting"), "{timings}");
    assert!(
        timings.contains("- meshopt vs rest-pose: bands apart on"),
        "{timings}"
    );
    // Its row of the table in docs/levels.md, with the columns that table has.
    let row = std::fs::read_to_string(out_dir.join("docs-row.md")).unwrap();
    assert!(row.starts_with("| cylinder | 240 | "), "{row}");
    let levels_md =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/levels.md"))
            .unwrap();
    let header = levels_md
        .lines()
        .skip_while(|l| *l != "<!-- error-table -->")
        .nth(1)
        .expect("docs/levels.md's error table");
    assert_eq!(
        header.matches('|').count(),
        row.trim_end().matches('|').count(),
        "{header}\n{row}"
    );
    assert!(json["methods"]["as"]["cache_hit_rate"].is_null());
    let png = image::open(out_dir.join("error.png")).unwrap();
    assert_eq!((png.width(), png.height()), (1000, 640));
    // Not blank: the curves' colours are there.
    let rgb = png.to_rgb8();
    let red = rgb
        .pixels()
        .filter(|p| p[0] > 180 && p[1] < 90 && p[2] < 90)
        .count();
    let blue = rgb.pixels().filter(|p| p[2] > 180 && p[0] < 80).count();
    assert!(red > 100 && blue > 100, "red {red}, blue {blue}");
    let md = std::fs::read_to_string(out_dir.join("timings.md")).unwrap();
    assert!(
        md.contains("| cylinder |") && md.contains("AS+IS/3D"),
        "{md}"
    );
    assert!(
        md.contains("Two methods are compared only where their bands separate"),
        "{md}"
    );
    assert!(md.contains("- as vs rest-pose: bands apart on"), "{md}");
    assert!(md.contains("at the same total influences"), "{md}");
    // The cylinder's texture coordinates are a parameterisation: the curves measure through
    // them. Every level the viewer bakes is there, with its silhouette at three tolerances.
    assert_eq!(json["correspondence"], "texture");
    assert!(md.contains("Measured by texture coordinates"), "{md}");
    for method in ["rest-pose", "as", "as+is"] {
        let levels = json["methods"][method]["levels"].as_array().unwrap();
        assert!(levels.len() >= 2, "{method}");
        for (k, l) in levels.iter().enumerate().skip(1) {
            let px = l["silhouette_px"].as_array().unwrap();
            assert_eq!(px.len(), 3, "{method} level {k}");
            let resolution = l["silhouette_resolution_px"].as_array().unwrap();
            assert_eq!(resolution.len(), 3, "{method} level {k}");
            assert!(resolution.iter().all(|r| r.as_f64().unwrap() >= 1.0));
            assert!(l["error"].as_f64().unwrap() >= l["bound"].as_f64().unwrap());
        }
        assert!(
            md.contains(&format!("### {method}: {} levels", levels.len())),
            "{md}"
        );
    }
}

#[test]
fn report_measures_a_model_without_texture_coordinates_by_closest_points() {
    let dir = tempfile::tempdir().unwrap();
    let mut flat = bent_cylinder(8, 8);
    flat.mesh.uvs.iter_mut().for_each(|u| *u = glam::Vec2::ZERO);
    let p = dir.path().join("no-uv.glb");
    std::fs::write(&p, to_glb(&flat)).unwrap();
    let out_dir = dir.path().join("r");
    let out = lodlab(&[
        "report",
        "--model",
        p.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        // Two tie orders: the bands by closest points, at a third of five's cost.
        "--orders",
        "2",
        "--cache",
        dir.path().join("cache").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("closest point"));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["correspondence"], "closest-point");
    // Without --baseline, timings.md says nothing of meshoptimizer.
    let timings = std::fs::read_to_string(out_dir.join("timings.md")).unwrap();
    assert!(!timings.contains("meshopt"), "{timings}");
    let md = std::fs::read_to_string(out_dir.join("timings.md")).unwrap();
    assert!(
        md.contains("Measured by closest point in the rest pose"),
        "{md}"
    );
    // The simplification still separates the methods.
    let curve = json["methods"]["as"]["curve"].as_array().unwrap();
    assert!(curve.last().unwrap()["rms_error"].as_f64().unwrap() > 0.0);
}

#[test]
fn report_survives_a_baseline_that_cannot_simplify() {
    // Every triangle its own texture chart: handed the charts welded at their points (as
    // meshopt's levels are), meshoptimizer finds every point a seam of three or more wedges and
    // moves none. The report says where it stops, and lodlab's own methods go on.
    let dir = tempfile::tempdir().unwrap();
    let cyl = bent_cylinder(8, 8);
    let mut confetti = cyl.clone();
    let m = &cyl.mesh;
    let out = &mut confetti.mesh;
    let (mut offsets, mut influences) = (vec![0u32], Vec::new());
    let (mut positions, mut normals, mut uvs, mut materials) = (vec![], vec![], vec![], vec![]);
    let side = (m.triangle_count() as f32).sqrt().ceil();
    for (t, tri) in m.indices.chunks_exact(3).enumerate() {
        let cell = glam::Vec2::new(t as f32 % side, (t as f32 / side).floor()) / side;
        for (k, &v) in tri.iter().enumerate() {
            let v = v as usize;
            positions.push(m.positions[v]);
            normals.push(m.normals[v]);
            materials.push(m.materials[v]);
            let corner = [glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y][k];
            uvs.push(cell + corner * 0.8 / side);
            let range = m.influence_offsets[v] as usize..m.influence_offsets[v + 1] as usize;
            influences.extend_from_slice(&m.influences[range]);
            offsets.push(influences.len() as u32);
        }
    }
    out.indices = (0..positions.len() as u32).collect();
    (out.positions, out.normals, out.uvs, out.materials) = (positions, normals, uvs, materials);
    (out.influence_offsets, out.influences) = (offsets, influences);
    let p = dir.path().join("confetti.glb");
    std::fs::write(&p, to_glb(&confetti)).unwrap();
    let out_dir = dir.path().join("r");
    let out = lodlab(&[
        "report",
        "--model",
        p.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--baseline",
        "meshopt",
        // Two tie orders: where meshoptimizer stops does not depend on them.
        "--orders",
        "2",
        "--cache",
        dir.path().join("cache").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("report.json")).unwrap()).unwrap();
    // Where it stops, said on stdout and in timings.md; its curve measures what it kept.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let timings = std::fs::read_to_string(out_dir.join("timings.md")).unwrap();
    for said in [&*stdout, &timings] {
        assert!(
            said.contains("meshopt's levels stop short at 128 triangles"),
            "{said}"
        );
    }
    let meshopt = json["methods"]["meshopt"]["curve"].as_array().unwrap();
    assert!(!meshopt.is_empty());
    let levels = json["methods"]["as"]["levels"].as_array().unwrap();
    let coarsest = levels.last().unwrap()["triangles"].as_u64().unwrap();
    assert!(coarsest < 240, "as keeps {coarsest} of 240 triangles");
}

/// `bake --json` prints the table's figures as JSON, and `--first-error` (e₁) cuts finer
/// levels when smaller; `--tolerance` is the run-time commands' and is refused here.
#[test]
fn bake_prints_json_and_names_its_first_error() {
    let dir = tempfile::tempdir().unwrap();
    let model = cylinder_glb(dir.path());
    let cache = dir.path().join("cache");
    let run = |e1: &str| {
        let out = lodlab(&[
            "bake",
            model.to_str().unwrap(),
            "--methods",
            "as",
            "--first-error",
            e1,
            "--cache",
            cache.to_str().unwrap(),
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        json
    };
    let fine = run("0.25");
    let c = &fine["characters"][0];
    assert_eq!(c["model"], "cylinder");
    assert_eq!(c["method"], "as");
    let levels = c["levels"].as_array().unwrap();
    assert_eq!(levels[0]["triangles"], c["source_triangles"]);
    assert!(levels[1]["error_mm"].as_f64().unwrap() > 0.0);
    let coarse = run("4");
    let e1 = |j: &serde_json::Value| {
        j["characters"][0]["levels"][1]["error_mm"]
            .as_f64()
            .unwrap()
    };
    assert!(e1(&coarse) > e1(&fine), "{} vs {}", e1(&coarse), e1(&fine));
    let out = lodlab(&["bake", model.to_str().unwrap(), "--tolerance", "1"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Levels cut by `bake --triangles` are what `--levels triangles:N,N` shows: the shot reads
/// the bake's cached cut (no second file of levels) and its forced level has the budget's
/// triangles.
#[test]
fn levels_cut_by_triangles_can_be_shown() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let out = lodlab(&[
        "bake",
        "robot",
        "--methods",
        "as",
        "--triangles",
        "200,120",
        "--cache",
        cache.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let baked: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let levels = baked["characters"][0]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    let files = || std::fs::read_dir(&cache).unwrap().count();
    let before = files();
    let png = dir.path().join("level.png");
    let out = lodlab(&[
        "shot",
        "--scene",
        "study",
        "--model",
        "robot",
        "--count",
        "1",
        "--method",
        "as",
        "--impostors",
        "off",
        "--levels",
        "triangles:200,120",
        "--force-level",
        "2",
        "--cache",
        cache.to_str().unwrap(),
        "--size",
        "64x64",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let shot: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(shot["triangles"], levels[2]["triangles"]);
    assert_eq!(files(), before, "the shot baked its own levels");
    // A malformed cut is one line.
    let out = lodlab(&[
        "shot",
        "--levels",
        "triangles:200,x",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("'x' is not a positive whole number"));
}

/// Options travel as values: two imports and two bakes in one process, at the same time, each
/// with its own limits, extra clips and level budgets, and neither sees the other's.
#[test]
fn two_models_bake_with_their_own_inputs_in_one_process() {
    use lodlab::import::{ImportOptions, import, validate::Limits};
    let plain = ImportOptions::default();
    let with_clips = ImportOptions {
        extra_clips: vec!["mocap-walk".into()],
        ..Default::default()
    };
    let mut few = Limits::default();
    few.set("triangles=100").unwrap();
    let tight = ImportOptions {
        limits: few,
        ..Default::default()
    };
    let (clipped, bare, refused) = std::thread::scope(|s| {
        let clipped = s.spawn(|| import("mocap", &with_clips));
        let bare = s.spawn(|| import("mocap", &plain));
        let refused = s.spawn(|| import("mocap", &tight));
        (
            clipped.join().unwrap().unwrap(),
            bare.join().unwrap().unwrap(),
            refused.join().unwrap(),
        )
    });
    assert!(clipped.model.clips.len() > bare.model.clips.len());
    assert_ne!(
        clipped.source_hash, bare.source_hash,
        "the clips are in the key"
    );
    let e = refused.unwrap_err().to_string();
    assert!(e.contains("--limit triangles="), "{e}");
    // The same inputs give the same key.
    assert_eq!(
        import("mocap", &with_clips).unwrap().source_hash,
        clipped.source_hash
    );
    assert_eq!(
        import("mocap", &plain).unwrap().source_hash,
        bare.source_hash
    );

    // Levels cut by error and by triangle budgets, baked side by side into one cache.
    let dir = tempfile::tempdir().unwrap();
    let path = cylinder_glb(dir.path());
    let cylinder = import(path.to_str().unwrap(), &plain).unwrap();
    let cache = LodCache::new(Some(dir.path().join("cache")));
    let bake = |budgets: Option<&[u32]>| {
        let options = lodlab::runtime::levels::runtime_options(&cylinder.model, budgets);
        let (lods, _) = load_or_bake(
            &cache,
            &cylinder.model,
            &cylinder.source_hash,
            Method::AnimationSpace,
            &options,
            &|_| {},
        );
        lods.levels
            .iter()
            .map(|l| l.mesh.triangle_count())
            .collect::<Vec<_>>()
    };
    let (by_error, by_budget) = std::thread::scope(|s| {
        let a = s.spawn(|| bake(None));
        let b = s.spawn(|| bake(Some(&[160, 120])));
        (a.join().unwrap(), b.join().unwrap())
    });
    assert_ne!(by_error, by_budget);
    assert_eq!(by_budget.len(), 3, "{by_budget:?}");
    assert!(by_budget[1] <= 160 && by_budget[2] <= 120, "{by_budget:?}");
}
