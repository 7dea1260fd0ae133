//! The figures of tests 1 to 8, drawn from the rows the runs measured beside the closed forms.

use super::closed_forms::*;
use super::runs::{Damping, ElasticImpact, Oblique, SpinRun, TangentialRow, Test3Row};
use crate::plot::{Color, Figure, LineStyle, MarkerShape, Panel, Series};

/// Up to `n` points of a history, evenly spread over the contact.
pub(super) fn thin<T: Copy>(points: &[T], n: usize) -> Vec<T> {
    let step = (points.len() / n.max(1)).max(1);
    points.iter().copied().step_by(step).collect()
}

pub(super) fn elastic_figure(test: usize, results: &[ElasticImpact]) -> Figure {
    let mut fo = Vec::new();
    let mut ft = Vec::new();
    for (k, r) in results.iter().enumerate() {
        let color = Color::palette(k);
        let contact: Vec<(f64, f64, f64)> = r.history.iter().copied().filter(|x| x.1 > 0.0).collect();
        let curve: Vec<(f64, f64)> = (0..=200)
            .map(|s| {
                let d = r.theory.overlap_max * s as f64 / 200.0;
                (d * 1e6, r.theory.stiffness * d.powf(1.5))
            })
            .collect();
        fo.push(Series::line(
            if k == 0 { "Hertz: (4/3)E*√R*·δ^1.5".to_string() } else { String::new() },
            curve,
            LineStyle::Thin,
            Color::BLACK,
        ));
        fo.push(Series::markers(
            format!("{}: grainflow", r.material),
            thin(&contact, 40).iter().map(|x| (x.1 * 1e6, x.2)).collect(),
            if k == 0 { MarkerShape::Circle } else { MarkerShape::Triangle },
            color,
        ));
        let dt = r.history.get(1).map_or(0.0, |x| x.0);
        let n = r.history.len().saturating_sub(1);
        let reference = hertz_overlap_history(r.theory.stiffness, r.m_star, r.v, dt, n, 8);
        let ref_curve: Vec<(f64, f64)> = r
            .history
            .iter()
            .zip(&reference)
            .filter(|(_, d)| **d > 0.0)
            .map(|(x, d)| (x.0 * 1e6, r.theory.stiffness * d.powf(1.5)))
            .collect();
        ft.push(Series::line(
            if k == 0 { "Hertz, RK4 integration".to_string() } else { String::new() },
            thin(&ref_curve, 400),
            LineStyle::Thin,
            Color::BLACK,
        ));
        ft.push(Series::markers(
            format!("{}: grainflow", r.material),
            thin(&contact, 40).iter().map(|x| (x.0 * 1e6, x.2)).collect(),
            if k == 0 { MarkerShape::Circle } else { MarkerShape::Triangle },
            color,
        ));
    }
    let what = if test == 1 {
        "two identical spheres (R = 10 mm) head-on at ±10 m/s"
    } else {
        "sphere (R = 0.1 m) on a rigid plane at 0.2 m/s"
    };
    Figure {
        title: format!("Chung & Ooi test {test}: {what}"),
        note: Some("Hertz, e = 1, μ = 0; markers every ~50 steps of Δt ≈ t_c/2000".into()),
        panels: vec![
            Panel {
                series: fo, ..Panel::new("Force against overlap", "overlap δ (µm)", "normal force (N)")
            },
            Panel { series: ft, ..Panel::new("Force against time", "time (µs)", "normal force (N)") },
        ],
    }
}

pub(super) fn test3_figure(rows: &[Test3Row]) -> Figure {
    let materials: Vec<String> =
        rows.first().map(|r| r.2.iter().map(|x| x.0.clone()).collect()).unwrap_or_default();
    // (input e, measured e) or (input e, 1e4 × error) of damping `d` and material `m`.
    let points = |d: Damping, m: &str, error: bool| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.0 == d)
            .filter_map(|r| {
                let v = r.2.iter().find(|x| x.0 == m)?.1;
                Some((r.1, if error { (v - r.1) * 1e4 } else { v }))
            })
            .collect()
    };
    let mut left =
        vec![Series::line("e_sim = e_input", vec![(0.15, 0.15), (1.0, 1.0)], LineStyle::Thin, Color::BLACK)];
    let mut right = Vec::new();
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle];
    for (k, m) in materials.iter().enumerate() {
        let c = Color::palette(k);
        for (j, clip) in [false, true].into_iter().enumerate() {
            let label = format!("{m}, exact, clip = {clip}");
            let color = if clip { Color::palette(k + 2) } else { c };
            left.push(Series::markers(
                label.clone(),
                points(Damping::Exact { clip }, m, false),
                shapes[j],
                color,
            ));
            right.push(Series::line(
                label,
                points(Damping::Exact { clip }, m, true),
                LineStyle::Solid,
                color,
            ));
        }
    }
    // The damping ratio does not depend on the material: one MFIX-formula curve shows both.
    if let Some(m) = materials.first() {
        left.push(Series::line(
            "MFIX's formula η = 2√(KM)|ln e|/√(π² + ln²e)",
            points(Damping::Mfix, m, false),
            LineStyle::Dashed,
            Color::PURPLE,
        ));
    }
    Figure {
        title: "Chung & Ooi test 3: normal restitution, Hertz law with a δ^¼ dashpot".into(),
        note: Some("R = 2.5 mm at 3.9 m/s on a rigid plane; damping solved for exact e (both clipping choices) vs MFIX's linear-law formula".into()),
        panels: vec![
            Panel {
                series: left,
                x_range: Some((0.15, 1.02)),
                y_range: Some((0.15, 1.02)),
                ..Panel::new("Measured against input restitution", "input e", "measured e")
            },
            Panel {
                series: right,
                x_range: Some((0.15, 1.02)),
                ..Panel::new("Error of the exact damping", "input e", "(e_sim − e_input) × 10⁴")
            },
        ],
    }
}

pub(super) fn test4_figure(rows: &[Oblique], speed: f64, r: f64, mu: f64, e: f64, threshold: f64) -> Figure {
    let thetas: Vec<f64> = (1..=87).map(|k| k as f64).collect();
    let panel = |q: usize, title: &str, y: &str| {
        let sliding: Vec<(f64, f64)> = thetas
            .iter()
            .filter(|&&t| t >= threshold - 8.0)
            .map(|&t| (t, gross_sliding_oblique(t, speed, r, mu, e)[q]))
            .collect();
        let rigid: Vec<(f64, f64)> =
            thetas.iter().map(|&t| (t, rigid_body_oblique(t, speed, r, mu, e)[q])).collect();
        let series = vec![
            Series::line("gross sliding (exact)", sliding, LineStyle::Solid, Color::GREY),
            Series::line(
                format!("rigid body (stick below {:.1}°)", (3.5 * mu * (1.0 + e)).atan().to_degrees()),
                rigid,
                LineStyle::Dashed,
                Color::BLACK,
            ),
            Series::markers(
                "grainflow, Hertz–Mindlin",
                rows.iter().map(|o| (o.theta, o.sim[q])).collect(),
                MarkerShape::Circle,
                Color::BLUE,
            ),
        ];
        Panel { series, x_range: Some((0.0, 90.0)), ..Panel::new(title, "impact angle θ (deg)", y) }
    };
    let mut p_et = panel(0, "Tangential restitution", "e_t = v_t′/v_t0");
    p_et.y_range = Some((0.5, 1.05));
    Figure {
        title: "Chung & Ooi test 4: Al oxide sphere on Al alloy at 3.9 m/s, μ = 0.092, e = 0.98".into(),
        note: Some(format!(
            "lever R; gross sliding exact above {threshold:.1}° (elastic threshold for Hertz–Mindlin), below it stick and micro-slip depend on the model"
        )),
        panels: vec![
            panel(2, "Rebound angle", "rebound angle α (deg)"),
            p_et,
            panel(1, "Angular velocity", "ω′ (rad/s)"),
        ],
    }
}

pub(super) fn test5_figure(rows: &[TangentialRow]) -> Figure {
    let mut materials: Vec<&str> = rows.iter().map(|r| r.material.as_str()).collect();
    materials.dedup();
    let x: Vec<f64> = (0..=150).map(|k| k as f64 * 0.1).collect();
    let mut p2 = vec![
        Series::line(
            "gross sliding: Ψ₂ = Ψ₁ − 7",
            x.iter().map(|&p| (p, p - 7.0)).collect(),
            LineStyle::Solid,
            Color::GREY,
        ),
        Series::line(
            "rigid body: stick (0) / slide",
            x.iter().map(|&p| (p, (p - 7.0).max(0.0))).collect(),
            LineStyle::Dashed,
            Color::BLACK,
        ),
    ];
    let mut pw = vec![
        Series::line("gross sliding: 5", vec![(0.0, 5.0), (15.0, 5.0)], LineStyle::Solid, Color::GREY),
        Series::line(
            "rigid body: min(5Ψ₁/7, 5)",
            x.iter().map(|&p| (p, (5.0 * p / 7.0).min(5.0))).collect(),
            LineStyle::Dashed,
            Color::BLACK,
        ),
    ];
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle];
    for (k, m) in materials.iter().enumerate() {
        let pts = |f: fn(&TangentialRow) -> f64| {
            rows.iter().filter(|r| r.material == *m).map(|r| (r.psi1, f(r))).collect()
        };
        p2.push(Series::markers(
            format!("grainflow, {m}"),
            pts(|r| r.psi2),
            shapes[k % 2],
            Color::palette(k),
        ));
        pw.push(Series::markers(
            format!("grainflow, {m}"),
            pts(|r| r.omega_norm),
            shapes[k % 2],
            Color::palette(k),
        ));
    }
    Figure {
        title: "Chung & Ooi test 5: v_n = 5 m/s, v_t = 0.1 … 21 m/s, μ = 0.3, e = 1, rigid plane".into(),
        note: Some("Ψ₁ = v_t/(μv_n), Ψ₂ = u′/(μv_n) with u′ the contact-point tangential velocity after impact; lever R".into()),
        panels: vec![
            Panel { series: p2, x_range: Some((0.0, 14.5)), ..Panel::new("Contact-point rebound", "Ψ₁", "Ψ₂") },
            Panel { series: pw, x_range: Some((0.0, 14.5)), ..Panel::new("Spin after impact", "Ψ₁", "Rω′/(μv_n)") },
        ],
    }
}

pub(super) fn spin_figure(test: usize, specified: &SpinRun, elastic: &SpinRun) -> Figure {
    let e = specified.e;
    let mut materials: Vec<&str> = specified.rows.iter().map(|r| r.material.as_str()).collect();
    materials.dedup();
    let shapes = [MarkerShape::Circle, MarkerShape::Triangle];
    let line = |x1: f64| {
        Series::line("sliding: β = x − 1", vec![(0.0, -1.0), (x1, x1 - 1.0)], LineStyle::Solid, Color::GREY)
    };
    let mut full = vec![line(3.0)];
    let mut zoom = vec![line(1.6)];
    let mut el = vec![line(1.6)];
    for (k, m) in materials.iter().enumerate() {
        let color = Color::palette(k);
        let pts = |run: &SpinRun| -> Vec<(f64, f64)> {
            run.rows.iter().filter(|r| r.material == *m).map(|r| (r.x, r.beta)).collect()
        };
        full.push(Series::line(format!("grainflow, {m}"), pts(specified), LineStyle::Solid, color));
        zoom.push(Series::markers(format!("grainflow, {m}"), pts(specified), shapes[k % 2], color));
        let corrected: Vec<(f64, f64)> = specified
            .rows
            .iter()
            .filter(|r| r.material == *m && r.x <= 1.0)
            .filter_map(|r| r.onset_loss.map(|l| (r.x, r.x - 1.0 - l)))
            .collect();
        zoom.push(Series::line(format!("x − 1 − Δβ_onset, {m}"), corrected, LineStyle::Dashed, color));
        el.push(Series::markers(format!("grainflow, e = 1, {m}"), pts(elastic), shapes[k % 2], color));
        if let Some(r) = elastic.rows.iter().find(|r| r.material == *m) {
            el.push(Series::line(
                format!("x_c = 7/(7 − 1/κ) = {:.3}, {m}", r.x_c),
                vec![(r.x_c, -1.1), (r.x_c, 1.0)],
                LineStyle::Dashed,
                color,
            ));
        }
    }
    let what = if test == 6 {
        "sphere (R = 0.1 m) onto a rigid plane"
    } else {
        "sphere (R₁ = 0.1 m) onto a sphere R₂ = 0.5 m, 1000× denser"
    };
    Figure {
        title: format!("Chung & Ooi test {test}: spinning {what}, v_n = 0.2 m/s, μ = 0.4"),
        note: Some("β = −u′/u₀ (u the contact-point slip, u₀ = R₁ω₀), x = 3.5μ(1 + e)v_n/u₀; ω₀ = 0.175 … 21 rad/s; lever R".into()),
        panels: vec![
            Panel {
                series: full,
                x_range: Some((0.0, 25.0)),
                y_range: Some((-1.1, 1.0)),
                ..Panel::new(format!("e = {e}, whole sweep"), "x", "β")
            },
            Panel {
                series: zoom,
                x_range: Some((0.0, 1.6)),
                y_range: Some((-1.0, 0.6)),
                ..Panel::new(format!("e = {e}: sliding branch and onset stick"), "x", "β")
            },
            Panel {
                series: el,
                x_range: Some((0.0, 3.0)),
                y_range: Some((-1.1, 1.0)),
                ..Panel::new("e = 1: exact up to x_c", "x = 7μv_n/u₀", "β")
            },
        ],
    }
}
