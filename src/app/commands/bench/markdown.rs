//! `lodlab bench`'s report as Markdown: the methods' figures, where each frame goes by pass,
//! how many times over each pass shades what it covers, and the instances by level kind.

use super::{BenchReport, COVERAGE_VIEWS, MethodFigures};
use crate::bake::gpu_data::drawable::LevelKind;
use crate::render::timer::Pass;
use std::fmt::Write as _;

/// The report as Markdown: a line on the set-up, the calibration, and a table, one row per
/// method in the order measured.
pub fn markdown(r: &BenchReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "lodlab bench: {} scene, {} instances, {}x{}, MSAA {}, {} transitions ({}-driven), \
         tolerance {} px; {} frames per method along the {} path ({} s), measured for {:.1} s \
         after {:.1} s of warm-up{} (once warm, {:.1} s more, announced as {:.0} s); {}.",
        r.scene,
        r.instances,
        r.size[0],
        r.size[1],
        r.msaa,
        r.transition,
        r.drive,
        r.tolerance_px,
        r.frames_per_method,
        r.path,
        r.path_seconds,
        r.measured_seconds,
        r.warmup_seconds,
        if r.coverage_seconds > 0.0 {
            format!(" and {:.1} s of coverage", r.coverage_seconds)
        } else {
            String::new()
        },
        r.rest_seconds,
        r.announced_seconds,
        if r.timing == "gpu timestamps" {
            "GPU time from timestamp queries"
        } else {
            "wall time per frame (no timestamp queries)"
        }
    );
    let _ = writeln!(
        out,
        "\nAdapter: {} ({}, driver {}).\n\nCalibration: {:.2} M triangles/s (trivial unskinned \
         shader on the frames of `{}`).\n",
        r.adapter,
        r.backend,
        if r.driver.is_empty() { "?" } else { &r.driver },
        r.calibration.triangles_per_second * 1e-6,
        r.calibration.method
    );
    out.push_str(
        "| method | median ms | p5 ms | p95 ms | FPS | triangles | vertices | influences | \
         efficiency | instances per level |\n",
    );
    out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for name in &r.order {
        let Some(f) = r.methods.get(name) else {
            continue;
        };
        let levels: Vec<String> = f.lod_histogram.iter().map(u32::to_string).collect();
        let _ = writeln!(
            out,
            "| {name} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {} | {} | {:.2} | {} |",
            f.median_ms,
            f.p5_ms,
            f.p95_ms,
            f.fps,
            f.triangles,
            f.vertices,
            f.influences,
            f.efficiency,
            levels.join(" / ")
        );
    }
    let cpu: Vec<String> = r
        .order
        .iter()
        .filter_map(|name| Some(format!("{name} {:.2} ms", r.methods.get(name)?.cpu_ms)))
        .collect();
    let _ = writeln!(
        out,
        "\nCPU per frame, selecting levels and encoding and uploading instances (median): {}.",
        cpu.join(", ")
    );
    out.push_str(&pass_table(r));
    out.push_str(&fragment_table(r));
    out.push_str(&kind_table(r));
    out
}

/// How many times over each pass shades the pixels it covers (medians over a few views along
/// the path); empty where the adapter does not count fragments.
fn fragment_table(r: &BenchReport) -> String {
    let drawn: Vec<Pass> = Pass::ALL
        .into_iter()
        .filter(|p| {
            r.methods
                .values()
                .any(|f| f.fragments_by_pass.contains_key(p.name()))
        })
        .collect();
    let heading = format!(
        "Fragments by pass (over {COVERAGE_VIEWS} views taken together: per pixel of the view \
         · per pixel the pass covers · share of the view it covers):"
    );
    method_table(r, &heading, &names(&drawn, Pass::name), |f| {
        drawn
            .iter()
            .map(|p| {
                f.fragments_by_pass.get(p.name()).map(|x| {
                    format!(
                        "{:.2} · {:.2} · {:.0}%",
                        x.per_pixel,
                        x.per_covered_pixel,
                        x.covered * 100.0
                    )
                })
            })
            .collect()
    })
}

/// Instances per frame by what their level shows (mean over the frames), and what each kind
/// costs drawn alone.
fn kind_table(r: &BenchReport) -> String {
    let kinds: Vec<LevelKind> = LevelKind::ALL
        .into_iter()
        .filter(|k| {
            r.methods
                .values()
                .any(|f| f.instances_by_kind.contains_key(k.name()))
        })
        .collect();
    let heading = "Instances by level kind (mean per frame):";
    let columns = names(&kinds, LevelKind::name);
    let mut out = method_table(r, heading, &columns, |f| {
        kinds
            .iter()
            .map(|k| {
                let x = f.instances_by_kind.get(k.name()).copied().unwrap_or(0.0);
                Some(format!("{x:.1}"))
            })
            .collect()
    });
    if r.methods.values().any(|f| !f.cost_by_kind.is_empty()) {
        let heading = format!(
            "Each level kind drawn alone (median over {COVERAGE_VIEWS} views: GPU ms of its \
             pass · fragments per pixel of the view):"
        );
        out.push_str(&method_table(r, &heading, &columns, |f| {
            kinds
                .iter()
                .map(|k| {
                    let [ms, x] = f.cost_by_kind.get(k.name())?;
                    Some(format!("{ms:.1} · {x:.2}"))
                })
                .collect()
        }));
    }
    out
}

/// Where each method's frame goes: the median GPU milliseconds of each pass, and the
/// fragments shaded per pixel; empty without timestamp queries.
fn pass_table(r: &BenchReport) -> String {
    let drawn: Vec<Pass> = Pass::ALL
        .into_iter()
        .filter(|p| r.methods.values().any(|f| f.passes.contains_key(p.name())))
        .collect();
    let overdraw = r.methods.values().any(|f| f.overdraw.is_some());
    let mut columns = names(&drawn, Pass::name);
    if overdraw && !drawn.is_empty() {
        columns.push("fragments per pixel");
    }
    method_table(r, "GPU time by pass (median ms):", &columns, |f| {
        let mut cells: Vec<Option<String>> = drawn
            .iter()
            .map(|p| f.passes.get(p.name()).map(|ms| format!("{ms:.1}")))
            .collect();
        if overdraw {
            cells.push(f.overdraw.map(|x| format!("{x:.2}")));
        }
        cells
    })
}

/// The names of `items`, as table columns.
fn names<T: Copy>(items: &[T], name: fn(T) -> &'static str) -> Vec<&'static str> {
    items.iter().map(|&i| name(i)).collect()
}

/// A Markdown table after `heading` with a row per method in the order measured and the
/// figures `cells` gives under `columns` (None: "–"); empty where there are no columns.
fn method_table(
    r: &BenchReport,
    heading: &str,
    columns: &[&str],
    cells: impl Fn(&MethodFigures) -> Vec<Option<String>>,
) -> String {
    if columns.is_empty() {
        return String::new();
    }
    let mut out = format!("\n{heading}\n\n| method |");
    for c in columns {
        let _ = write!(out, " {c} |");
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(columns.len()));
    out.push('\n');
    for name in &r.order {
        let Some(f) = r.methods.get(name) else {
            continue;
        };
        let _ = write!(out, "| {name} |");
        for cell in cells(f) {
            let _ = write!(out, " {} |", cell.as_deref().unwrap_or("–"));
        }
        out.push('\n');
    }
    out
}
