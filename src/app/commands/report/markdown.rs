//! The report's Markdown: bake times, levels and their errors, shading with and without
//! normal maps.

use crate::app::commands::report::compare::VISIBLE_COLOUR;
use crate::app::commands::report::data::{Report, SHADING_PX, SILHOUETTE_POSES};
use crate::bake::character::lod::LodOptions;
use crate::bake::character::simplify::{Method, Sequence};
use crate::model::Model;

/// Table 1 of the paper for this model, the levels with their silhouettes, and how the
/// methods compare.
pub(crate) fn timings_markdown(
    report: &Report,
    model: &Model,
    sequences: &[(Method, Sequence)],
    lod_opts: &LodOptions,
) -> String {
    let t = |n: &str| report.methods.get(n).map(|m| m.bake_seconds);
    let (rest, asm, asis) = (t("rest-pose"), t("as"), t("as+is"));
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        _ => "–".into(),
    };
    let secs = |x: Option<f64>| x.map_or("–".into(), |x| format!("{x:.3}"));
    let is_stats = sequences
        .iter()
        .find(|(m, _)| *m == Method::InfluenceSimplification)
        .map(|(_, s)| &s.stats);
    let miss = is_stats
        .and_then(|s| s.cache_hit_rate())
        .map_or("–".into(), |h| format!("{:.4}%", (1.0 - h) * 100.0));
    let influences_per_vertex =
        model.mesh.influences.len() as f64 / model.mesh.vertex_count().max(1) as f64;
    let mut md = format!(
        "# Bake timings for {} (Table 1 of Merry et al.)\n\n\
         Memoryless simplification and cutting the levels (measuring each against full\n\
         detail), release build, one method at a time. 3D is simplification of the rest pose;\n\
         AS uses the L2,2 metric; AS+IS adds influence simplification. Cache miss rate:\n\
         influence-simplification factorisations not found in the {}-entry cache.\n\n\
         | Model | Vertices | Bones | Influences per vertex | 3D (s) | AS (s) | AS+IS (s) | AS/3D | AS+IS/3D | Cache miss rate |\n\
         |---|---|---|---|---|---|---|---|---|---|\n\
         | {} | {} | {} | {:.2} | {} | {} | {} | {} | {} | {} |\n",
        report.model,
        crate::bake::character::simplify::influence::CACHE_SIZE,
        report.model,
        report.vertices,
        report.bones,
        influences_per_vertex,
        secs(rest),
        secs(asm),
        secs(asis),
        ratio(asm, rest),
        ratio(asis, rest),
        miss
    );
    if let Some(m) = report.methods.get("meshopt") {
        md += &format!(
            "\nmeshoptimizer (`meshopt::simplify` on the rest pose) takes {:.3} s for one level at \
             the coarsest triangle count.\n",
            m.bake_seconds
        );
    }
    md += &levels_markdown(report, lod_opts);
    md += &shading_markdown(report);
    md += &comparison_markdown(report);
    md
}

/// The methods compared at equal influence counts, where their bands separate.
fn comparison_markdown(report: &Report) -> String {
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("–".into(), |x| format!("{:.0}%", x * 100.0));
    let mut md = format!(
        "\n## Error at equal influence counts\n\n\
         Measured by {}, over {} surface samples and {} frames. Each method was baked in {} tie \
         orders (the order steps of equal cost are taken in; the order a file lists its \
         vertices in changes nothing): its curve is their median, its band the lowest to the \
         highest. Two methods are compared only where their bands separate; where they overlap, \
         the tie orders alone part them as far, and the points count for neither.\n\n{}",
        report.correspondence.describe(),
        report.samples,
        report.frames,
        report.orders,
        report
            .stillness()
            .map_or(String::new(), |s| format!("Note: {s}.\n\n")),
    );
    md += "| method | median band (highest − lowest) / median | fewest influences |\n|---|---:|---:|\n";
    for (name, m) in &report.methods {
        md += &format!(
            "| {name} | {} | {} |\n",
            m.band.map_or("–".into(), |b| format!("{:.1}%", b * 100.0)),
            c.min_influences.get(name).copied().unwrap_or(0)
        );
    }
    md += "\n";
    for (pair, s) in &c.separations {
        md += &format!(
            "- {pair}: bands apart on {} of the curve, the first better on {} of that ({} \
             better, {} indistinguishable, {} worse): {}\n",
            pct(Some(s.better + s.worse)),
            pct(s.better_where_separate()),
            pct(Some(s.better)),
            pct(Some(s.indistinguishable)),
            pct(Some(s.worse)),
            s.says
        );
    }
    if let Some(line) = meshopt_floor(report) {
        md += &format!("- {line}\n");
    }
    md += &format!(
        "- AS better than rest-pose on {} of the points where they separate down to the \
         coarsest level (not beyond); AS / rest-pose {} at the median\n\
         - AS+IS's lighting (colour error by vertex normals) at most {} AS's at the same \
         total influences, over the levels where either shows {VISIBLE_COLOUR} or more\n",
        pct(c.as_le_rest_pose_at_levels),
        c.as_over_rest_pose
            .map_or("–".into(), |r| format!("{r:.2}")),
        c.as_is_lighting_over_as
            .map_or("–".into(), |r| format!("{r:.2}×")),
    );
    md
}

/// Every level's lighting against full detail's, per method: vertex normals against the
/// normal map.
pub(crate) fn shading_markdown(report: &Report) -> String {
    let mut md = format!(
        "\n## Lighting\n\n\
         Each level's colour error against full detail, {SHADING_PX} px high: the mean colour \
         difference (0 to 1) over the pixels either covers, divided by the pixels full detail \
         covers, from {} views 15° above the ground at {} times of the first clip. Both columns \
         draw the same triangles, lit by the level's own vertex normals or through its normal \
         map (full detail's normals baked on its texture coordinates); their difference is the \
         lighting alone. The worst tile is the same error over the {}-pixel tile where it is \
         largest (of those full detail mostly covers): where a mean hides a streak. Recoloured: \
         the share of the pixels both cover that show a colour full detail shows nowhere within \
         the level's error of them (a part's colour bleeding onto another's).\n",
        crate::measure::colour_error::METRIC_VIEWS,
        crate::measure::colour_error::METRIC_FRAMES,
        crate::measure::shading_error::TILE,
    );
    let measured: Vec<_> = report
        .methods
        .iter()
        .filter(|(_, m)| !m.shading.is_empty())
        .collect();
    if measured.is_empty() {
        md += "\nNot measured: no GPU adapter.\n";
    }
    for (name, m) in measured {
        md += &format!(
            "\n### {name}\n\n| LOD | triangles | vertex normals | normal map | change | worst tile, vertex normals | worst tile, normal map | recoloured |\n|---|---|---|---|---|---|---|---|\n"
        );
        for s in &m.shading {
            let change = if !s.mapped {
                "no map".to_string()
            } else if s.vertex_normals > 0.0 {
                format!("{:+.0}%", 100.0 * (s.normal_maps / s.vertex_normals - 1.0))
            } else {
                "–".to_string()
            };
            md += &format!(
                "| {} | {} | {:.5} | {:.5} | {change} | {:.4} | {:.4} | {:.2}% |\n",
                s.level,
                s.triangles,
                s.vertex_normals,
                s.normal_maps,
                s.worst_tile_vertex_normals,
                s.worst_tile_normal_maps,
                100.0 * s.recoloured
            );
        }
    }
    md
}

/// The levels the viewer bakes, per method: triangles, error, bound, and the silhouette
/// distance at each tolerance; the coarsest level's triangles against the source's.
pub(crate) fn levels_markdown(report: &Report, lod_opts: &LodOptions) -> String {
    let taus: Vec<String> = report
        .silhouette_tolerances
        .iter()
        .map(|t| format!("silhouette at {t} px"))
        .collect();
    let mut md = format!(
        "\n## Levels\n\n\
         As the viewer bakes them (LOD 1 within {:.2} mm, each level's error doubling; a \
         level's error is the larger of the memoryless bound and the distance measured from \
         full detail, closest points both ways, worst of {} poses). The silhouette columns are \
         the largest distance in pixels between the level's silhouette and full detail's where \
         the renderer switches to the level at that tolerance, over {} poses from {} \
         directions. Where a level's error is so small that drawing it at that scale would \
         exceed {} pixels, the drawing is capped, and the bracket says how many pixels one \
         drawn pixel spans: the measurement's resolution there.\n",
        lod_opts.base_error * 1000.0,
        crate::bake::character::lod::POSE_SAMPLES,
        SILHOUETTE_POSES,
        crate::bake::character::silhouette::VIEWS.len(),
        crate::bake::character::silhouette::MAX_SIDE,
    );
    for (name, m) in &report.methods {
        if m.levels.is_empty() {
            continue;
        }
        let coarsest = m.levels.last().map_or(0, |l| l.triangles);
        md += &format!(
            "\n### {name}: {} levels, the coarsest {} triangles ({:.1}% of {})\n\n\
             | LOD | triangles | influences | error (mm) | bound (mm) | {} |\n|---|---|---|---|---|{}\n",
            m.levels.len(),
            coarsest,
            100.0 * coarsest as f64 / report.triangles.max(1) as f64,
            report.triangles,
            taus.join(" | "),
            "---|".repeat(taus.len()),
        );
        for (k, l) in m.levels.iter().enumerate() {
            let sil: Vec<String> = if l.silhouette_px.is_empty() {
                vec!["–".into(); taus.len()]
            } else {
                l.silhouette_px
                    .iter()
                    .zip(&l.silhouette_resolution_px)
                    .map(|(d, pixel)| {
                        if *pixel > 1.01 {
                            format!("{d:.2} (1 px = {pixel:.1})")
                        } else {
                            format!("{d:.2}")
                        }
                    })
                    .collect()
            };
            md += &format!(
                "| {k} | {} | {} | {:.3} | {:.3} | {} |\n",
                l.triangles,
                l.influences,
                l.error * 1000.0,
                l.bound * 1000.0,
                sil.join(" | ")
            );
        }
    }
    md
}

/// This model's row of the table of error curves and bake times in `docs/levels.md`, as the
/// report measured it (`docs-row.md`): `tools/docs/error-table.sh` builds that table from
/// these rows, so that its figures are what `report` prints, not copied by hand.
pub(crate) fn docs_row(report: &Report) -> String {
    let c = &report.comparison;
    let pct = |x: Option<f64>| x.map_or("–".into(), |x| format!("{:.0}%", x * 100.0));
    let each = |f: &dyn Fn(&crate::app::commands::report::data::MethodReport) -> String| {
        ["rest-pose", "as", "as+is"]
            .map(|m| report.methods.get(m).map_or("–".into(), f))
            .join(" / ")
    };
    let apart = |pair: &str| {
        c.separations.get(pair).map_or("–".into(), |s| {
            format!(
                "{} ({} apart)",
                pct(s.better_where_separate()),
                pct(Some(s.better + s.worse))
            )
        })
    };
    let triangles = crate::app::viewer::figures::thousands(report.triangles as u64);
    format!(
        "| {} | {triangles} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
        report.model,
        each(&|m| format!("{:.2}", m.bake_seconds)),
        each(&|m| m
            .levels
            .last()
            .map_or("–".into(), |l| l.triangles.to_string())),
        each(&|m| m.band.map_or("–".into(), |b| format!("{:.0}%", b * 100.0))),
        apart("as vs rest-pose"),
        pct(c.as_le_rest_pose_at_levels),
        c.as_over_rest_pose
            .map_or("–".into(), |r| format!("{r:.2}")),
        apart("as+is vs as"),
        c.as_is_lighting_over_as
            .map_or("–".into(), |r| format!("{r:.2}×")),
    )
}

/// Where meshoptimizer's levels end against the floor the papers' methods reach, in words;
/// `None` where the report has no meshopt levels.
pub(crate) fn meshopt_floor(report: &Report) -> Option<String> {
    let coarsest = report.methods.get("meshopt")?.levels.last()?.triangles;
    let floor = report
        .methods
        .get("rest-pose")
        .and_then(|r| r.levels.last())
        .map_or(0, |l| l.triangles);
    Some(if coarsest > floor {
        format!(
            "meshopt's levels stop short at {coarsest} triangles (rest-pose reaches {floor}): \
             seams and borders meshoptimizer will not move"
        )
    } else {
        format!("meshopt's levels reach {coarsest} triangles, as far as rest-pose's")
    })
}
