//! The report's outputs: its Markdown, its charts, and the files `write` puts in a folder.

use super::*;

/// The Markdown tables: per zoom, RMSE and mean ΔE of every method per configuration, then the
/// averages with the time per frame.
pub fn markdown(rep: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Report: {}\n\nAdapter: {}. Object: {}. {}×{} pixels, reference {} rays per pixel. Times: {}.\n\n\
         Ground truth at N rays is a prefix of the reference's ray sequence (its RMSE is σ√(1/N − 1/R)); \
         the reference's own noise is the RMSE between its first half and all of it (column `ref. noise`). \
         `RMSE beyond ref. noise` takes the reference's per-pixel noise (from its squared sums) out of each \
         method's mean squared error.\n",
        rep.preset, rep.adapter, rep.object, rep.size.0, rep.size.1, rep.reference_spp, rep.timing
    );
    let names: Vec<String> = rep
        .configs
        .first()
        .map(|c| c.methods.iter().map(|m| m.method.clone()).collect())
        .unwrap_or_default();
    let mut zooms: Vec<f64> = rep.configs.iter().map(|c| c.distance).collect();
    zooms.dedup();
    for z in zooms {
        let cs: Vec<&ConfigResult> = rep.configs.iter().filter(|c| c.distance == z).collect();
        let _ = writeln!(s, "## Distance {z}: RMSE (linear RGB) / mean ΔE*ab\n");
        let _ = writeln!(s, "| view | light | ref. noise | {} |", names.join(" | "));
        let _ = writeln!(s, "|---|---|---|{}", "---|".repeat(names.len()));
        for c in &cs {
            let cells: Vec<String> = c
                .methods
                .iter()
                .map(|m| format!("{:.4} / {:.2}", m.rmse, m.delta_e_mean))
                .collect();
            let _ = writeln!(
                s,
                "| {}° | {} | {:.4} | {} |",
                c.view_deg,
                c.light,
                c.reference_noise,
                cells.join(" | ")
            );
        }
        let _ = writeln!(s, "\nAverages over the configurations above:\n");
        let _ = writeln!(
            s,
            "| method | RMSE | RMSE beyond ref. noise | mean ΔE | p95 ΔE | ms/frame |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for (i, name) in names.iter().enumerate() {
            let avg = |f: &dyn Fn(&MethodResult) -> f64| {
                cs.iter().map(|c| f(&c.methods[i])).sum::<f64>() / cs.len().max(1) as f64
            };
            let _ = writeln!(
                s,
                "| {name} | {:.4} | {:.4} | {:.2} | {:.2} | {:.1} |",
                avg(&|m| m.rmse),
                avg(&|m| m.rmse_beyond_noise),
                avg(&|m| m.delta_e_mean),
                avg(&|m| m.delta_e_p95),
                avg(&|m| m.ms)
            );
        }
        let _ = writeln!(s);
    }
    s.push_str(&crate::report::adaptive::markdown(&adaptive_rows(rep)));
    if rep.configs.iter().any(|c| c.prediction.is_some()) {
        let _ = writeln!(
            s,
            "Predicted deviation of one ray (the model's σ̂, what the ray counts follow) against the \
             reference's measured per-pixel deviation; and the ray gain at equal error that per-pixel \
             counts buy where the error is each pixel's variance: the best (Neyman's allocation on the \
             measured deviations, which no per-pixel counts exceed) and the model's (its first-round \
             weights). A gain beyond the best needs a reconstruction across pixels.\n\n\
             | configuration | pixels | rank correlation | log correlation | median predicted/measured | per-pixel counts' gain: best / the model's |\n\
             |---|---|---|---|---|---|"
        );
        for c in &rep.configs {
            if let Some(p) = &c.prediction {
                let _ = writeln!(
                    s,
                    "| {}° d {} light {} | {} | {:.2} | {:.2} | {:.2} | {:.2} / {:.2} |",
                    c.view_deg,
                    c.distance,
                    c.light,
                    p.pixels,
                    p.rank_correlation,
                    p.log_correlation,
                    p.median_ratio,
                    p.best_allocation_gain,
                    p.predicted_allocation_gain
                );
            }
        }
        let _ = writeln!(s);
    }
    s
}

/// Each configuration's name with its uniform and adaptive ground truth.
fn adaptive_rows(rep: &Report) -> Vec<(String, &[UniformPoint], &[AdaptiveResult])> {
    rep.configs
        .iter()
        .map(|c| {
            (
                format!("{}° d {} light {}", c.view_deg, c.distance, c.light),
                c.uniform.as_slice(),
                c.adaptive.as_slice(),
            )
        })
        .collect()
}

/// One chart series: label, colour, points, joined by a line.
const COLORS: [&str; 5] = ["#d62728", "#1f77b4", "#ff7f0e", "#2ca02c", "#555555"];

/// Error (mean ΔE*ab: robust, unlike RMSE, to the few firefly pixels near the horizon) against time
/// (log–log; one point per method averaged over the configurations, a curve for ground truth over
/// rays per pixel) and against view angle per method (light at the normal, middle zoom): file stem,
/// chart and its series.
pub fn charts(rep: &Report) -> Vec<(&'static str, Chart, Vec<Series>)> {
    let names: Vec<String> = rep
        .configs
        .first()
        .map(|c| c.methods.iter().map(|m| m.method.clone()).collect())
        .unwrap_or_default();
    let n = rep.configs.len().max(1) as f64;
    let avg = |i: usize, f: &dyn Fn(&MethodResult) -> f64| {
        rep.configs.iter().map(|c| f(&c.methods[i])).sum::<f64>() / n
    };
    let mut series = Vec::new();
    let mut truth_curve = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let p = (avg(i, &|m| m.ms), avg(i, &|m| m.delta_e_mean));
        if name.starts_with("ground truth") {
            truth_curve.push(p);
        } else {
            series.push((name.clone(), COLORS[series.len() % 4], vec![p], false));
        }
    }
    series.push((
        "ground truth, 1…256 spp".into(),
        COLORS[4],
        truth_curve,
        true,
    ));
    let time_chart = Chart {
        title: format!("{}: error against time", rep.preset),
        x_label: "ms per frame (log)".into(),
        y_label: "mean ΔE*ab vs reference (log)".into(),
        log_x: true,
        log_y: true,
    };
    let time_series = series;
    let mut zooms: Vec<f64> = rep.configs.iter().map(|c| c.distance).collect();
    zooms.dedup();
    let mid = zooms.get(zooms.len() / 2).copied().unwrap_or(0.0);
    let mut series = Vec::new();
    for (i, name) in names.iter().enumerate() {
        if name.starts_with("ground truth") && name != "ground truth 16 spp" {
            continue;
        }
        let pts: Vec<(f64, f64)> = rep
            .configs
            .iter()
            .filter(|c| c.distance == mid && c.light == "normal")
            .map(|c| (c.view_deg, c.methods[i].delta_e_mean))
            .collect();
        series.push((name.clone(), COLORS[series.len() % 5], pts, true));
    }
    let view_chart = Chart {
        title: format!(
            "{}: error against view angle (distance {mid}, light at the normal)",
            rep.preset
        ),
        x_label: "view angle from the normal (degrees)".into(),
        y_label: "mean ΔE*ab vs reference (log)".into(),
        log_x: false,
        log_y: true,
    };
    let mut charts = vec![
        ("error_vs_time", time_chart, time_series),
        ("error_vs_view", view_chart, series),
    ];
    if let Some((chart, series)) = crate::report::adaptive::chart(&rep.preset, &adaptive_rows(rep))
    {
        charts.push(("error_vs_rays", chart, series));
    }
    charts
}

/// Write report.json, report.md and the charts error_vs_time and error_vs_view, each as PNG and
/// SVG, into `dir`.
pub fn write(rep: &Report, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let put = |name: &str, text: String| {
        let path = dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    put("report.json", serde_json::to_string_pretty(rep)?)?;
    put("report.md", markdown(rep))?;
    for (stem, chart, series) in charts(rep) {
        put(&format!("{stem}.svg"), chart.svg(&series))?;
        let png = dir.join(format!("{stem}.png"));
        chart
            .png(&series)
            .save(&png)
            .with_context(|| format!("writing {}", png.display()))?;
    }
    Ok(())
}
