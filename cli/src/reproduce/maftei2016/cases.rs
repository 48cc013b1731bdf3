//! The `coagula validate` cases of Maftei et al. (2016) and the first-hits scenario
//! files `coagula run` takes.

use super::*;

/// The `coagula validate` cases under `maftei2016/`: the Langevin schemes against exact
/// references (the scheme's own moments away from walls, the folded motion of a
/// specular wall, the free-flight kernel), each within the suite's `t·SE` threshold.
pub fn cases(quick: bool) -> Result<Vec<crate::cases::Case>, String> {
    use coagula_core::langevin::kernel::free_flight;
    use coagula_core::langevin::{Batch, Config, Field, Scalar, euler_moments, folded_normal_mean};
    use coagula_core::observe::{TEST_ALPHA, student_t_threshold};
    let n: u64 = if quick { 1 << 17 } else { 1 << 21 };
    let case = |name: &str, quantity: &str, reference: f64, r: &Replicas| {
        let tolerance = student_t_threshold(TEST_ALPHA, r.count() - 1) * r.std_error();
        let error = (r.mean() - reference).abs();
        crate::cases::Case {
            case: format!("maftei2016/{name}"),
            quantity: quantity.into(),
            reference,
            value: r.mean(),
            error,
            tolerance,
            pass: error < tolerance,
        }
    };
    // (ids 0..n of one key per case; chunks merge in order)
    let batches = |make: &(dyn Fn(u64, u64) -> Result<Vec<[f64; 3]>, String> + Sync)| -> Result<[Replicas; 3], String> {
        let parts = over_chunks(true, n.div_ceil(CHUNK), |c| {
            make(c * CHUNK, CHUNK.min(n - c * CHUNK))
        })?;
        let mut out = [Replicas::new(); 3];
        for v in parts.iter().flatten() {
            for k in 0..3 {
                out[k].push(v[k]);
            }
        }
        Ok(out)
    };
    let mut out = Vec::new();
    // free Ornstein–Uhlenbeck velocity, far from the wall: the scheme's exact moments
    let (g, s, h, steps) = (0.7, 1.3, 0.05, 40u64);
    let [mx, mu, _, _, vuu] = euler_moments(1e6, 0.5, g, s, h, steps);
    let r = batches(&|id0, m| {
        let cfg = Config::line(h, s, Wall::Specular).map_err(err)?;
        let mut b = Batch::with_starts(cfg, Friction { rate: g }, m as usize, 1, id0, |_| {
            ([1e6], [0.5])
        })
        .map_err(err)?;
        b.advance_to(h * steps as f64).map_err(err)?;
        Ok(b.positions()
            .zip(b.velocities())
            .map(|(x, u)| [x[0] - 1e6, u[0], (u[0] - mu) * (u[0] - mu)])
            .collect())
    })?;
    out.push(case(
        "free-motion",
        "E x_T - x0 (exact moments of the scheme)",
        mx - 1e6,
        &r[0],
    ));
    out.push(case(
        "free-motion",
        "Var u_T (exact moments of the scheme)",
        vuu,
        &r[2],
    ));
    // b = 0 next to a specular wall: the folded free motion
    let (h, steps) = (0.02, 50u64);
    let [mx, mu, vxx, vxu, vuu] = euler_moments(0.3, -0.8, 0.0, 1.0, h, steps);
    let r = batches(&|id0, m| {
        let cfg = Config::line(h, 1.0, Wall::Specular).map_err(err)?;
        let mut b = Batch::with_starts(cfg, Scalar(|_, _, _| 0.0), m as usize, 2, id0, |_| {
            ([0.3], [-0.8])
        })
        .map_err(err)?;
        b.advance_to(h * steps as f64).map_err(err)?;
        Ok(b.positions()
            .zip(b.velocities())
            .map(|(x, u)| [x[0], x[0] * u[0], u[0] * u[0]])
            .collect())
    })?;
    out.push(case(
        "specular-mirror",
        "E X_T (b = 0: the folded free Gaussian)",
        folded_normal_mean(mx, vxx),
        &r[0],
    ));
    out.push(case("specular-mirror", "E X_T U_T", vxu + mx * mu, &r[1]));
    out.push(case("specular-mirror", "E U_T^2", vuu + mu * mu, &r[2]));
    // the free-flight kernel from first hits (exact at any step)
    let p = FirstHits {
        radius: 0.5,
        outer: 10.0,
        from: 0.4,
        to: 1.0,
        dt: 0.1,
        sigma: 0.0,
        velocity_sd: 1.0,
        trajectories: n,
    };
    let (k3, _) =
        kernel_on_threads::<3, _>(&p, &Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]), 3)?;
    out.push(case(
        "kernel-free-flight-3d",
        "first-hit kernel vs pi R^2 <|v|>",
        free_flight(3, 0.5, 1.0),
        &k3,
    ));
    let (k2, _) =
        kernel_on_threads::<2, _>(&p, &Field(|_, _: &[f64; 2], _: &[f64; 2]| [0.0; 2]), 4)?;
    out.push(case(
        "kernel-free-flight-2d",
        "first-hit kernel vs 2 R <|v|>",
        free_flight(2, 0.5, 1.0),
        &k2,
    ));
    Ok(out)
}

/// A first-hit kernel scenario (`coagula run` of a file with a `[first-hits]` table).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FirstHitsFile {
    #[allow(dead_code)]
    title: Option<String>,
    #[serde(rename = "first-hits")]
    first_hits: FirstHitsSpec,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FirstHitsSpec {
    #[serde(default = "three")]
    dim: u32,
    radius: f64,
    diffusivity: f64,
    relaxation: f64,
    #[serde(default)]
    shear: f64,
    window: [f64; 2],
    dt: f64,
    trajectories: u64,
    #[serde(default)]
    outer: f64,
    #[serde(default)]
    seed: u64,
}

fn three() -> u32 {
    3
}

/// Runs a first-hit kernel scenario: the estimate with its 95% interval, the hits, and
/// Smoluchowski's Brownian and orthokinetic kernels for comparison; JSON with `json`.
pub fn first_hits_scenario(name: &str, text: &str, json: bool) -> Result<(), String> {
    use coagula_core::langevin::Shear;
    use coagula_core::langevin::kernel::orthokinetic;
    let f: FirstHitsFile = toml::from_str(text).map_err(|e| format!("{name}: {e}"))?;
    let s = f.first_hits;
    let bad = |what: &str| Err(format!("{name}: first-hits.{what}"));
    if !(s.relaxation > 0.0 && s.relaxation.is_finite()) {
        return bad("relaxation must be finite and > 0");
    }
    if !(s.diffusivity >= 0.0 && s.diffusivity.is_finite()) {
        return bad("diffusivity must be finite and >= 0");
    }
    if !s.shear.is_finite() {
        return bad("shear must be finite");
    }
    let (from, to) = (s.window[0], s.window[1]);
    let reach = 8.0 * (2.0 * s.diffusivity * to).sqrt();
    let outer = if s.outer == 0.0 {
        // pairs from beyond cannot meet before `to`: diffusion, and advection by the
        // shear across the sphere's band
        s.radius + reach + s.shear.abs() * (s.radius + reach) * to
    } else {
        s.outer
    };
    let tau = s.relaxation;
    let p = FirstHits {
        radius: s.radius,
        outer,
        from,
        to,
        dt: s.dt,
        sigma: (2.0 * s.diffusivity).sqrt() / tau,
        velocity_sd: (s.diffusivity / tau).sqrt(),
        trajectories: s.trajectories,
    };
    let drift = Shear {
        rate: 1.0 / tau,
        shear: s.shear,
    };
    let start = Instant::now();
    if s.trajectories == 0 {
        return bad("trajectories must be at least 1");
    }
    let n = s.trajectories;
    let (rep, hits) = match s.dim {
        2 => kernel_on_threads::<2, _>(&p, &drift, s.seed)?,
        3 => kernel_on_threads::<3, _>(&p, &drift, s.seed)?,
        d => return Err(format!("{name}: first-hits.dim = {d} (2 or 3)")),
    };
    let e = Estimate::of(&rep);
    let (lo, hi) = e.ci95();
    let brownian = if s.dim == 3 && s.diffusivity > 0.0 {
        Some(smoluchowski(s.diffusivity, s.radius, from, to))
    } else {
        None
    };
    let ortho = (s.dim == 3 && s.shear != 0.0).then(|| orthokinetic(s.shear.abs(), s.radius));
    let secs = start.elapsed().as_secs_f64();
    if json {
        let v = serde_json::json!({
            "kernel": e.mean, "std_error": e.std_error, "ci95": [lo, hi], "hits": hits,
            "trajectories": n, "outer": outer, "seconds": secs,
            "smoluchowski_brownian": brownian, "smoluchowski_orthokinetic": ortho,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&v).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    println!(
        "{name}: first-hit kernel, {n} trajectories, dim {}, outer radius {outer:.3}",
        s.dim
    );
    println!(
        "kernel = {:.6} ± {:.6} (95% CI [{lo:.6}, {hi:.6}]), {hits} first hits in [{from}, {to}), {secs:.1} s",
        e.mean, e.std_error
    );
    println!(
        "persistence sqrt(D tau)/R = {:.4}; step dt/tau = {:.3}",
        (s.diffusivity * tau).sqrt() / s.radius,
        s.dt / tau
    );
    if let Some(b) = brownian {
        println!("Smoluchowski, Brownian (with its transient, over the window): {b:.6}");
    }
    if let Some(o) = ortho {
        println!("Smoluchowski, orthokinetic (4/3) shear R^3: {o:.6}");
    }
    Ok(())
}
