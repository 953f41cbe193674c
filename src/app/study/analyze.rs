//! `lodlab study analyze`: per condition, how often each method was preferred, and whether the
//! preference could be chance: a two-sided binomial (sign) test against p = ½, as Merry et al.
//! §6.2 report theirs. Training answers are left out.

use super::plan::{Condition, read_manifest};
use super::session::{TEST, read_all_answers};
use crate::app::plotting::{plot_error, register_font, write_plot};
use crate::atomic::write as write_atomic;
use anyhow::Result;
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ConditionResult {
    pub condition: Condition,
    /// Test answers (training left out).
    pub answers: usize,
    pub prefer_a: usize,
    pub prefer_b: usize,
    /// Share of answers preferring method B.
    pub share_b: f64,
    /// Two-sided binomial test of prefer_b out of answers against ½.
    pub p_value: f64,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Analysis {
    /// The answer files read (the desktop's answers.csv, the online study's downloads) and the
    /// answers each added.
    pub answer_files: Vec<(String, usize)>,
    pub participants: usize,
    pub training_answers_left_out: usize,
    pub conditions: Vec<ConditionResult>,
    /// How well each metric of the image-metric proxy (`study proxy`) predicted the answers,
    /// where it ran (empty where not).
    pub proxy: Vec<ProxyAgreement>,
}

/// One metric of the proxy against the participants: over the conditions that have answers,
/// the rank correlation (Spearman's ρ) between how much the metric favours B (SSIM B − A, or
/// ꟻLIP A − B) and the share of answers preferring B; and how often the metric's choice was
/// the majority's.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ProxyAgreement {
    pub metric: String,
    /// How much the metric favours B in every condition, in the order of `conditions`.
    pub differences: Vec<f64>,
    /// Over all conditions with answers (None: fewer than three, or no spread).
    pub rho: Option<f64>,
    /// Conditions with a majority (share B ≠ ½) and where the metric chose as it did.
    pub decided: usize,
    pub agreed: usize,
    /// ρ within each method pair, over its models and tolerances.
    pub per_pair: Vec<PairAgreement>,
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PairAgreement {
    pub method_a: crate::scene::LodMethod,
    pub method_b: crate::scene::LodMethod,
    pub conditions: usize,
    pub rho: Option<f64>,
}

/// Metric `m` of the proxy against `conditions` (see [`ProxyAgreement`]).
fn agreement(
    proxy: &super::proxy::Proxy,
    m: usize,
    conditions: &[ConditionResult],
) -> ProxyAgreement {
    let differences: Vec<f64> = conditions
        .iter()
        .map(|r| {
            proxy
                .conditions
                .iter()
                .find(|p| p.condition == r.condition)
                .map_or(0.0, |p| p.favour_b()[m])
        })
        .collect();
    let answered: Vec<(usize, &ConditionResult)> = conditions
        .iter()
        .enumerate()
        .filter(|(_, r)| r.answers > 0)
        .collect();
    let rho_of = |rows: &[(usize, &ConditionResult)]| {
        let d: Vec<f64> = rows.iter().map(|(i, _)| differences[*i]).collect();
        let share: Vec<f64> = rows.iter().map(|(_, r)| r.share_b).collect();
        super::proxy::spearman(&d, &share)
    };
    let decided: Vec<&(usize, &ConditionResult)> =
        answered.iter().filter(|(_, r)| r.share_b != 0.5).collect();
    let agreed = decided
        .iter()
        .filter(|(i, r)| (differences[*i] > 0.0) == (r.share_b > 0.5) && differences[*i] != 0.0)
        .count();
    let mut pairs: Vec<(crate::scene::LodMethod, crate::scene::LodMethod)> = Vec::new();
    for (_, r) in &answered {
        let key = (r.condition.method_a, r.condition.method_b);
        if !pairs.contains(&key) {
            pairs.push(key);
        }
    }
    let per_pair = pairs
        .into_iter()
        .map(|(a, b)| {
            let rows: Vec<(usize, &ConditionResult)> = answered
                .iter()
                .filter(|(_, r)| r.condition.method_a == a && r.condition.method_b == b)
                .copied()
                .collect();
            PairAgreement {
                method_a: a,
                method_b: b,
                conditions: rows.len(),
                rho: rho_of(&rows),
            }
        })
        .collect();
    ProxyAgreement {
        metric: proxy.metrics[m].clone(),
        rho: rho_of(&answered),
        decided: decided.len(),
        agreed,
        differences,
        per_pair,
    }
}

/// ln n!
fn ln_factorial(n: usize) -> f64 {
    (2..=n).map(|k| (k as f64).ln()).sum()
}

/// Two-sided exact binomial test of `k` successes in `n` trials against p = ½: the probability,
/// under chance, of an outcome at most as likely as `k` (R's `binom.test`, which for p = ½ is
/// twice the smaller tail, capped at 1).
pub fn binomial_two_sided(k: usize, n: usize) -> f64 {
    if n == 0 {
        return 1.0;
    }
    let ln_n = ln_factorial(n);
    let ln_half = n as f64 * 0.5f64.ln();
    let ln_pmf = |i: usize| ln_n - ln_factorial(i) - ln_factorial(n - i) + ln_half;
    let observed = ln_pmf(k.min(n));
    // A relative tolerance, as R uses, so that ties in probability count on both sides.
    let p: f64 = (0..=n)
        .map(ln_pmf)
        .filter(|&l| l <= observed + 1e-7)
        .map(f64::exp)
        .sum();
    p.min(1.0)
}

pub fn analyze(dir: &Path) -> Result<Analysis> {
    let manifest = read_manifest(dir)?;
    let all = read_all_answers(dir)?;
    for (file, bad) in &all.unreadable {
        eprintln!(
            "warning: {}: {bad} line(s) could not be read and are left out",
            dir.join(file).display()
        );
    }
    if all.repeated > 0 {
        eprintln!(
            "warning: {}: {} answer(s) to trials answered in an earlier file are left out \
             (the first answer counts)",
            dir.display(),
            all.repeated
        );
    }
    let answers = all.answers;
    let training = answers.iter().filter(|a| a.block != TEST).count();
    let conditions: Vec<ConditionResult> = manifest
        .conditions
        .iter()
        .map(|c| {
            let of_c: Vec<_> = answers
                .iter()
                .filter(|a| {
                    a.block == TEST
                        && a.model == c.model
                        && a.method_a == c.method_a
                        && a.method_b == c.method_b
                        && a.tolerance_px == c.tolerance_px
                })
                .collect();
            let prefer_b = of_c.iter().filter(|a| a.preferred == c.method_b).count();
            let prefer_a = of_c.iter().filter(|a| a.preferred == c.method_a).count();
            let n = prefer_a + prefer_b;
            ConditionResult {
                condition: c.clone(),
                answers: n,
                prefer_a,
                prefer_b,
                share_b: if n > 0 {
                    prefer_b as f64 / n as f64
                } else {
                    0.5
                },
                p_value: binomial_two_sided(prefer_b, n),
            }
        })
        .collect();
    let participants = {
        let mut ids: Vec<&str> = answers.iter().map(|a| a.participant.as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        ids.len()
    };
    let proxy = match super::proxy::read(dir)? {
        Some(p) => (0..p.metrics.len())
            .map(|m| agreement(&p, m, &conditions))
            .collect(),
        None => Vec::new(),
    };
    Ok(Analysis {
        answer_files: all.files,
        participants,
        training_answers_left_out: training,
        conditions,
        proxy,
    })
}

/// The table: one row per condition.
pub fn markdown(a: &Analysis) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Study analysis: {} participant(s) answered; {} training answer(s) left out. p: \
         two-sided binomial (sign) test against no preference.\n",
        a.participants, a.training_answers_left_out
    );
    if a.answer_files
        .iter()
        .any(|(f, _)| f != super::plan::ANSWERS)
    {
        let files: Vec<String> = a
            .answer_files
            .iter()
            .map(|(f, n)| format!("{f} ({n})"))
            .collect();
        let _ = writeln!(out, "Answers read from: {}.\n", files.join(", "));
    }
    out.push_str(
        "| model | A vs B | tolerance px | answers | prefer A | prefer B | share B | p |\n",
    );
    out.push_str("|---|---|---:|---:|---:|---:|---:|---:|\n");
    for r in &a.conditions {
        let c = &r.condition;
        let _ = writeln!(
            out,
            "| {} | {} vs {} | {} | {} | {} | {} | {} | {} |",
            c.model,
            c.method_a,
            c.method_b,
            c.tolerance_px,
            r.answers,
            r.prefer_a,
            r.prefer_b,
            if r.answers > 0 {
                format!("{:.0}%", r.share_b * 100.0)
            } else {
                "–".into()
            },
            if r.answers > 0 {
                format_p(r.p_value)
            } else {
                "–".into()
            }
        );
    }
    for p in &a.proxy {
        let rho = |r: Option<f64>| {
            r.map_or("n/a (fewer than 3 conditions, or no spread)".into(), |r| {
                format!("{r:+.3}")
            })
        };
        let _ = writeln!(
            out,
            "\nImage-metric proxy, {}: Spearman's ρ between how much it favours B and the \
             share preferring B, over the conditions with answers: {}. It chose as the \
             majority did in {} of {} conditions with a majority.\n",
            p.metric,
            rho(p.rho),
            p.agreed,
            p.decided
        );
        out.push_str("| A vs B | conditions | ρ |\n|---|---:|---:|\n");
        for q in &p.per_pair {
            let _ = writeln!(
                out,
                "| {} vs {} | {} | {} |",
                q.method_a,
                q.method_b,
                q.conditions,
                q.rho.map_or("n/a".into(), |r| format!("{r:+.3}"))
            );
        }
        out.push_str(
            "\n| model | A vs B | tolerance px | share B | favours B by |\n|---|---|---:|---:|---:|\n",
        );
        for (r, d) in a.conditions.iter().zip(&p.differences) {
            let c = &r.condition;
            let _ = writeln!(
                out,
                "| {} | {} vs {} | {} | {:.0}% | {d:+.4} |",
                c.model,
                c.method_a,
                c.method_b,
                c.tolerance_px,
                r.share_b * 100.0
            );
        }
    }
    out
}

fn format_p(p: f64) -> String {
    let stars = if p < 0.001 {
        " ***"
    } else if p < 0.01 {
        " **"
    } else if p < 0.05 {
        " *"
    } else {
        ""
    };
    if p < 0.0001 {
        format!("{p:.1e}{stars}")
    } else {
        format!("{p:.4}{stars}")
    }
}

/// A bar per condition: the share of answers preferring method B, against the line of no
/// preference.
pub fn chart(a: &Analysis, path: &Path) -> Result<()> {
    register_font();
    let n = a.conditions.len().max(1);
    let (w, h) = ((200 + 210 * n as u32).max(700), 520u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Which clip looked better? Share preferring method B",
                ("sans-serif", 24),
            )
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(70)
            // A segmented range 0..k holds k + 1 segments: one a condition.
            .build_cartesian_2d((0..n as u32 - 1).into_segmented(), 0.0..1.0)
            .map_err(plot_error)?;
        let labels: Vec<String> = a
            .conditions
            .iter()
            .map(|r| {
                let c = &r.condition;
                format!(
                    "{} {} px: {} vs {}",
                    c.model, c.tolerance_px, c.method_a, c.method_b
                )
            })
            .collect();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n)
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels.get(*i as usize).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .x_label_style(("sans-serif", 14))
            .y_desc("share of answers preferring B")
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(plot_error)?;
        let significant = RGBColor(40, 110, 200);
        let not = RGBColor(170, 180, 195);
        let p_values: Vec<f64> = a.conditions.iter().map(|r| r.p_value).collect();
        chart
            .draw_series(
                Histogram::vertical(&chart)
                    .margin(25)
                    .style_func(|x, _| {
                        let i = match x {
                            SegmentValue::Exact(i) | SegmentValue::CenterOf(i) => *i as usize,
                            SegmentValue::Last => 0,
                        };
                        if p_values.get(i).is_some_and(|&p| p < 0.05) {
                            significant.filled()
                        } else {
                            not.filled()
                        }
                    })
                    .data(
                        a.conditions
                            .iter()
                            .enumerate()
                            .map(|(i, r)| (i as u32, r.share_b)),
                    ),
            )
            .map_err(plot_error)?;
        chart
            .draw_series(a.conditions.iter().enumerate().map(|(i, r)| {
                Text::new(
                    format!("n {}, p {}", r.answers, format_p(r.p_value)),
                    (SegmentValue::Exact(i as u32), (r.share_b + 0.04).min(0.97)),
                    ("sans-serif", 13),
                )
            }))
            .map_err(plot_error)?;
        chart
            .draw_series(LineSeries::new(
                [(SegmentValue::Exact(0), 0.5), (SegmentValue::Last, 0.5)],
                BLACK.stroke_width(2),
            ))
            .map_err(plot_error)?
            .label("no preference")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(SegmentValue::Exact(0), 0.0), (SegmentValue::Exact(0), 0.0)],
                significant.filled(),
            )))
            .map_err(plot_error)?
            .label("p < 0.05")
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 6), (x + 14, y + 6)], significant.filled())
            });
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// Analyses a study folder and writes `analysis.md`, `analysis.json` and `preferences.png` into
/// it.
pub fn run(dir: &Path) -> Result<Analysis> {
    let a = analyze(dir)?;
    // No answers is no result: a share of 50% and a p of 1 would read as one.
    if a.conditions.iter().all(|r| r.answers == 0) {
        anyhow::bail!(
            "{}: no answers yet, nothing to analyze (a participant answers in `lodlab study run {} --participant ID`, or online in the page `study web` writes)",
            dir.join(super::plan::ANSWERS).display(),
            dir.display()
        );
    }
    write_atomic(&dir.join("analysis.md"), markdown(&a).as_bytes())?;
    write_atomic(
        &dir.join("analysis.json"),
        crate::app::json::pretty(&a)?.as_bytes(),
    )?;
    chart(&a, &dir.join("preferences.png"))?;
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One condition's bar stands in the middle of the chart, not in the left half of an
    /// axis made for two.
    #[test]
    fn one_condition_fills_its_chart() {
        let condition = |model: &str| ConditionResult {
            condition: Condition {
                model: model.into(),
                method_a: crate::scene::LodMethod::ALL[1],
                method_b: crate::scene::LodMethod::ALL[2],
                tolerance_px: 1.5,
            },
            answers: 10,
            prefer_a: 2,
            prefer_b: 8,
            share_b: 0.8,
            p_value: 0.1,
        };
        for n in [1, 2, 3] {
            let a = Analysis {
                answer_files: Vec::new(),
                participants: 1,
                training_answers_left_out: 0,
                conditions: (0..n).map(|i| condition(&format!("m{i}"))).collect(),
                proxy: Vec::new(),
            };
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("p.png");
            chart(&a, &path).unwrap();
            let img = image::open(&path).unwrap().to_rgb8();
            let xs: Vec<u32> = img
                .enumerate_pixels()
                .filter(|(_, _, p)| p.0 == [170, 180, 195])
                .map(|(x, _, _)| x)
                .collect();
            assert!(!xs.is_empty(), "{n}: no bars");
            let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / xs.len() as f64;
            let centre = img.width() as f64 / 2.0;
            // The bars balance round the middle of the plot (its y labels pull it right a
            // little).
            assert!(
                (mean - centre).abs() < 0.08 * img.width() as f64,
                "{n}: bars' mean x {mean}, centre {centre}"
            );
        }
    }

    #[test]
    fn binomial_p_values_match_known_values() {
        // Exact values, as R's binom.test(k, n, 0.5) gives them (two-sided).
        let cases = [
            (9, 10, 0.021484375),
            (1, 10, 0.021484375),
            (5, 10, 1.0),
            (15, 20, 0.04138947),
            (5, 5, 0.0625),
            (0, 1, 1.0),
            (60, 92, 0.0046091),
            (35, 46, 0.00053559),
        ];
        for (k, n, p) in cases {
            let got = binomial_two_sided(k, n);
            assert!(
                (got - p).abs() <= 1e-4 * p.max(1e-3),
                "{k} of {n}: {got} against {p}"
            );
        }
        assert_eq!(binomial_two_sided(0, 0), 1.0);
        // Symmetric, and never above 1.
        for n in 1..40 {
            for k in 0..=n {
                let p = binomial_two_sided(k, n);
                assert!((p - binomial_two_sided(n - k, n)).abs() < 1e-12);
                assert!(p > 0.0 && p <= 1.0);
            }
        }
    }
}
