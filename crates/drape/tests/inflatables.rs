//! Gas in the volumes the fabric encloses (issue 47, `[[cavity]]`): the
//! gas laws along a run, the thin sphere's pressure–radius relation,
//! Hencky's problem reached by gas, an inflator with a vent, the energy
//! balance, and the errors of the `[[cavity]]` table.

mod common;

use common::{assert_error, build, column, drive_through, read_history, setup, temp_dir};
use drape::simulation::run;
use std::path::Path;

const AMBIENT: f64 = 101_325.0;

/// A closed sphere of radius 0.1 m (SVK, E t = 500 N/m) with `cavity`
/// (its `[[cavity]]` keys) between a floor and a plate moving down at 0.1
/// m/s, penalty contact, damped Newmark, `steps` of 5 ms.
fn cushion(cavity: &str, steps: usize) -> String {
    format!(
        r#"
[mesh]
shape = "sphere"
radius = 0.1
subdivisions = 2
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 500.0
thickness = 5.0e-4
[[cavity]]
{cavity}
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, -0.1]
normal = [0.0, 0.0, 1.0]
[[obstacle]]
shape = "plane"
point = [0.0, 0.0, 0.1]
normal = [0.0, 0.0, -1.0]
velocity = [0.0, 0.0, -0.1]
[contact]
method = "penalty"
penalty = 1.0e5
[time]
beta = 1.0
gamma = 1.5
segments = [{{ steps = {steps}, dt = 5.0e-3 }}]
[output]
every = 1000
[[monitor]]
name = "top"
at = [0.0, 0.0, 0.1]
"#
    )
}

/// Boyle's law: a closed isothermal cushion squeezed by a rigid plate
/// keeps `p V` at every step to 1e-6 relative (it is the invariant of the
/// step's law, so round-off is all that may change it); the adiabatic one
/// keeps `p V^gamma`. The plate does squeeze: the volume falls and the
/// pressure rises, more for the adiabatic gas (the same volume change
/// costs `gamma` times the pressure).
#[test]
fn boyle_cushion_squeezed_by_a_plate_keeps_its_gas_invariant() {
    for (law, exponent) in [("isothermal", 1.0), ("adiabatic", 1.4)] {
        let text = cushion(&format!("gas = \"{law}\"\npressure = 105000.0"), 80);
        let s = setup(&text);
        let dir = temp_dir(&format!("boyle-{law}"));
        run(&s, &dir, &mut |_| {}).unwrap();
        let (header, rows) = read_history(&dir);
        let v = column(&header, &rows, "cavity0_volume");
        let p = column(&header, &rows, "cavity0_pressure");
        let m = column(&header, &rows, "cavity0_mass");
        let top = column(&header, &rows, "top_z");
        let invariant: Vec<f64> = v
            .iter()
            .zip(&p)
            .map(|(v, p)| p * v.powf(exponent))
            .collect();
        for (k, c) in invariant.iter().enumerate() {
            assert!(
                (c / invariant[0] - 1.0).abs() < 1e-6,
                "{law}, step {k}: {c} vs {}",
                invariant[0]
            );
            assert_eq!(m[k], m[0], "{law}: a closed cushion keeps its gas");
        }
        // The plate went down 4 cm; the volume fell from its largest.
        assert!(
            top[top.len() - 1] < 0.065,
            "{law}: top at {}",
            top[top.len() - 1]
        );
        let largest = v.iter().copied().fold(0.0, f64::max);
        let last = v[v.len() - 1];
        assert!(last < (1.0 - 1e-3) * largest, "{law}: {last} vs {largest}");
        assert!(p[p.len() - 1] > p.iter().copied().fold(f64::INFINITY, f64::min));
    }
}

/// The thin sphere of SVK membrane (Green strain `E = (l^2 - 1)/2`
/// equibiaxial, membrane force per current length `n = t S`, `S = Y E /
/// (1 - nu)`): `p - p_amb = 2 n / r = t Y (l - 1/l) / ((1 - nu) R0)`, and
/// the isothermal gas `p = m R T / (4/3 pi R0^3 l^3)`. The stretch solving
/// both, by bisection (the left side rises with `l`, the right falls).
fn thin_sphere_stretch(mass: f64, r0: f64, ty: f64, nu: f64, rt: f64) -> f64 {
    let v0 = 4.0 / 3.0 * std::f64::consts::PI * r0.powi(3);
    let f =
        |l: f64| AMBIENT + ty * (l - 1.0 / l) / ((1.0 - nu) * r0) - mass * rt / (v0 * l.powi(3));
    let (mut lo, mut hi) = (0.5, 5.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A spherical balloon of SVK membrane given a mass of gas inflates
/// (statically, one increment) to the thin sphere's radius within 0.5 %,
/// for a small and a large stretch; the radius is the volume's, `(3 V /
/// 4 pi)^(1/3)`. The mesh's curved T6 triangles hold the sphere's volume
/// to about 1e-4 (its own discretisation error); the rest is the
/// membrane's (docs/validation.md has the figures).
#[test]
fn balloon_radius_matches_the_thin_sphere() {
    let (r0, e, t, nu, r_gas, temp) = (0.1, 1.0e6, 5.0e-4, 0.3, 287.05, 293.15);
    for target in [1.05f64, 1.3] {
        // The mass that gives about `target` (the test's stretch is the
        // bisection's, not this guess).
        let v = 4.0 / 3.0 * std::f64::consts::PI * (r0 * target).powi(3);
        let p = AMBIENT + t * e * (target - 1.0 / target) / ((1.0 - nu) * r0);
        let mass = p * v / (r_gas * temp);
        let text = format!(
            r#"
[mesh]
shape = "sphere"
radius = {r0}
subdivisions = 2
order = 2
[material]
youngs_modulus = {e}
poisson_ratio = {nu}
density = 1000.0
thickness = {t}
[[cavity]]
gas = "isothermal"
mass = {mass:e}
[[fix]]
at = [0.0, 0.0, 0.1]
[[fix]]
at = [0.0, 0.0, -0.1]
components = ["x", "y"]
[[fix]]
at = [0.1, 0.0, 0.0]
components = ["y"]
[analysis]
kind = "static"
steps = 1
"#
        );
        let s = setup(&text);
        let dir = temp_dir("balloon");
        let summary = run(&s, &dir, &mut |_| {}).unwrap();
        let volume = summary.cavities[0].volume;
        let radius = (3.0 * volume / (4.0 * std::f64::consts::PI)).cbrt();
        let expected = r0 * thin_sphere_stretch(mass, r0, t * e, nu, r_gas * temp);
        let error = radius / expected - 1.0;
        println!(
            "balloon, stretch {target}: radius {radius} m, thin sphere {expected} m ({error:e})"
        );
        assert!(
            error.abs() < 5e-3,
            "target {target}: {radius} vs {expected} ({error:e})"
        );
    }
}

/// Hencky's disc (examples/inflated-disc.toml) with its pressure made by
/// gas: the disc clamped on a rigid chamber of 2 m^3 (closed by the
/// disc's plane through the origin) filled with air at 101380 Pa. At rest
/// the gas's net pressure is some `q`; the same disc under the prescribed
/// pressure `q` rises as much at its centre, within 0.1 % (measured: to
/// the digits the runs settle to, docs/validation.md).
#[test]
fn hencky_reached_by_gas_rises_as_under_the_same_pressure() {
    let example = include_str!("../../../examples/inflated-disc.toml");
    let load = "[[load]]\nkind = \"pressure\"\nvalue = 28.70\nramp = 0.1\n";
    assert!(example.contains(load));
    let gas = example.replace(
        load,
        "[[cavity]]\ngas = \"isothermal\"\norigin = [0.0, 0.0, 0.0]\nchamber = 2.0\npressure = 101380.0\n",
    );
    let s = setup(&gas);
    let dir = temp_dir("hencky-gas");
    let by_gas = run(&s, &dir, &mut |_| {}).unwrap();
    assert!(by_gas.kinetic_energy < 1e-12, "not at rest");
    let q = by_gas.cavities[0].pressure - AMBIENT;
    let w_gas = by_gas.monitors["center"][2];
    let prescribed = example.replace("value = 28.70", &format!("value = {q:e}"));
    let s = setup(&prescribed);
    let dir = temp_dir("hencky-pressure");
    let by_pressure = run(&s, &dir, &mut |_| {}).unwrap();
    let w = by_pressure.monitors["center"][2];
    println!("Hencky by gas: q = {q} Pa, w0 {w_gas} m by gas, {w} m by pressure");
    assert!((w_gas / w - 1.0).abs() < 1e-3, "{w_gas} vs {w} at q = {q}");
    // Hencky's regime: w0/a about 0.1.
    assert!((w / 0.15 - 0.1).abs() < 0.01, "{w}");
}

/// An inflator fills a bag (a closed sphere at ambient pressure,
/// adiabatic, Wang–Nefske) with a vent: at every step the mass in the
/// bag is its initial mass plus the inflow less the outflow to 1e-9
/// relative, the inflow is the table's integral to the time, the vent
/// lets gas out once the pressure rises, and the pressure never falls
/// below ambient; the gas's energy balance (its internal energy against
/// the enthalpy in and out and its work on the fabric) holds to 1e-9.
#[test]
fn inflator_and_vent_balance_the_gas_mass() {
    let table: [[f64; 2]; 4] = [[0.0, 0.0], [0.02, 0.05], [0.06, 0.05], [0.08, 0.0]];
    let text = format!(
        r#"
[mesh]
shape = "sphere"
radius = 0.1
subdivisions = 2
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 500.0
thickness = 5.0e-4
[[cavity]]
gas = "adiabatic"
inflator = {{ mass_flow = {table:?}, temperature = 600.0, cp = 1040.0, cv = 743.0 }}
[[cavity.vent]]
area = 2.0e-4
discharge = 0.6
[[fix]]
at = [0.0, 0.0, -0.1]
[time]
beta = 1.0
gamma = 1.5
segments = [{{ steps = 60, dt = 2.0e-3 }}]
[output]
every = 1000
"#
    );
    let s = setup(&text);
    let dir = temp_dir("inflator");
    run(&s, &dir, &mut |_| {}).unwrap();
    let (header, rows) = read_history(&dir);
    let time = column(&header, &rows, "time");
    let m = column(&header, &rows, "cavity0_mass");
    let inflow = column(&header, &rows, "cavity0_inflow");
    let outflow = column(&header, &rows, "cavity0_outflow");
    let p = column(&header, &rows, "cavity0_pressure");
    let integral = |t: f64| {
        // The table's trapezoids up to t.
        let mut sum = 0.0;
        for w in table.windows(2) {
            let (t0, t1) = (w[0][0], w[1][0].min(t));
            if t1 > t0 {
                let r1 = w[0][1] + (w[1][1] - w[0][1]) * (t1 - t0) / (w[1][0] - w[0][0]);
                sum += 0.5 * (w[0][1] + r1) * (t1 - t0);
            }
        }
        sum
    };
    for k in 0..rows.len() {
        let balance = m[0] + inflow[k] - outflow[k];
        assert!(
            (m[k] - balance).abs() <= 1e-9 * m[k],
            "step {k}: {} vs {balance}",
            m[k]
        );
        assert!((inflow[k] - integral(time[k])).abs() <= 1e-12, "step {k}");
        assert!(p[k] >= AMBIENT * (1.0 - 1e-12), "step {k}: {}", p[k]);
    }
    let last = rows.len() - 1;
    assert!(
        outflow[last] > 0.01 * inflow[last],
        "the vent let out {}",
        outflow[last]
    );
    assert!(
        m[last] > m[0],
        "the bag holds more gas than it started with"
    );
    // The gas's first law, step by step (Wang & Nefske; docs/theory.md
    // §1.16): its internal energy `m c_v T` changes by the inflator's
    // enthalpy in, the vent's enthalpy out (at the step's starting
    // temperature) and the work it does on the fabric — the gas's part of
    // `external_work`, net of ambient, plus the ambient's `p_amb dV`.
    let (cv, cp, t_in) = (743.0, 1040.0, 600.0);
    let temperature = column(&header, &rows, "cavity0_temperature");
    let volume = column(&header, &rows, "cavity0_volume");
    let work = column(&header, &rows, "external_work");
    let u = |k: usize| m[k] * cv * temperature[k];
    let mut enthalpy = 0.0;
    let mut largest: f64 = 0.0;
    for k in 1..rows.len() {
        enthalpy += (inflow[k] - inflow[k - 1]) * cp * t_in
            - (outflow[k] - outflow[k - 1]) * cp * temperature[k - 1];
        let done = work[k] + AMBIENT * (volume[k] - volume[0]);
        let gap = (u(k) - u(0)) - (enthalpy - done);
        largest = largest.max(gap.abs() / u(k));
        assert!(
            gap.abs() <= 1e-9 * u(k),
            "step {k}: the gas's energy changed by {} J, the balance says {} J",
            u(k) - u(0),
            enthalpy - done
        );
    }
    eprintln!(
        "first law: largest gap {largest:.1e} of the internal energy ({:.1} J in, the work {:.3} J)",
        enthalpy,
        work[last] + AMBIENT * (volume[last] - volume[0])
    );
}

/// A closed adiabatic balloon let go above its equilibrium pressure
/// oscillates without dissipation (trapezoidal Newmark, beta = 1/4, gamma
/// = 1/2); the gas's work is in `external_work`, so `total_energy`
/// (kinetic + strain - work) stays at its start, 0, within 1 % of the
/// energy exchanged (the largest kinetic energy): the trapezoidal rule's
/// error on a nonlinear system (measured: 0.04 % over the first 16 ms of
/// the expansion, 80 steps).
#[test]
fn closed_balloon_keeps_its_total_energy() {
    let text = r#"
[mesh]
shape = "sphere"
radius = 0.1
subdivisions = 2
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 500.0
thickness = 5.0e-4
[[cavity]]
gas = "adiabatic"
pressure = 104000.0
[[fix]]
at = [0.0, 0.0, -0.1]
[time]
beta = 0.25
gamma = 0.5
segments = [{ steps = 80, dt = 2.0e-4 }]
[output]
every = 1000
"#;
    let s = setup(text);
    let dir = temp_dir("balloon-energy");
    run(&s, &dir, &mut |_| {}).unwrap();
    let (header, rows) = read_history(&dir);
    let total = column(&header, &rows, "total_energy");
    let kinetic = column(&header, &rows, "kinetic_energy");
    let work = column(&header, &rows, "external_work");
    let swing = kinetic.iter().copied().fold(0.0, f64::max);
    assert!(swing > 0.0 && work.iter().any(|w| *w > 0.5 * swing));
    let drift = total.iter().fold(0.0f64, |d, e| d.max(e.abs()));
    println!("closed balloon: total energy drift {drift:e} J of {swing:e} J");
    assert!(drift < 0.01 * swing, "drift {drift:e} of {swing:e}");
}

/// The `[[cavity]]` table's errors name the key, its value and the line.
#[test]
fn cavity_errors_name_the_key_and_value() {
    let disc = "[mesh]\nshape = \"disc\"\nradius = 0.1\nrings = 3\n\
        [material]\nyoungs_modulus = 1.0e6\npoisson_ratio = 0.3\ndensity = 500.0\nthickness = 5.0e-4\n";
    // A disc is not closed (and nothing holds its rim).
    assert_error(
        &format!("{disc}[[cavity]]\ngas = \"isothermal\"\npieces = [0]\n"),
        12,
        "cavity[0].pieces",
        &[
            "= [0] selects a surface that is not closed",
            "the edge between nodes",
            "origin",
        ],
    );
    let sphere = "[mesh]\nshape = \"sphere\"\nradius = 0.1\nsubdivisions = 1\n\
        [material]\nyoungs_modulus = 1.0e6\npoisson_ratio = 0.3\ndensity = 500.0\nthickness = 5.0e-4\n";
    let inflator = "inflator = { mass_flow = [[0.0, 0.0], [0.01, -2.0]], temperature = 600.0, cp = 1040.0, cv = 743.0 }\n";
    assert_error(
        &format!("{sphere}[[cavity]]\ngas = \"adiabatic\"\n{inflator}"),
        12,
        "cavity[0].inflator",
        &["mass_flow[1] = [0.01, -2]", "negative mass flow"],
    );
    // The sphere's surface is about 0.12 m^2.
    assert_error(
        &format!(
            "{sphere}[[cavity]]\ngas = \"adiabatic\"\n[[cavity.vent]]\narea = 1.0e-4\n[[cavity.vent]]\narea = 0.2\n"
        ),
        15,
        "cavity[0].vent[1].area",
        &["= 0.2 m^2", "larger than the bag", "its surface is"],
    );
    // An unknown law and an unknown key: serde's errors, with the line.
    for (table, line, fragments) in [
        (
            "gas = \"helium\"\n",
            11,
            &["unknown variant `helium`", "isothermal"][..],
        ),
        (
            "gas = \"adiabatic\"\npresure = 2.0e5\n",
            12,
            &["unknown field `presure`", "pressure"][..],
        ),
    ] {
        let text = format!("{sphere}[[cavity]]\n{table}");
        let e = build(&text, Path::new("test.toml")).unwrap_err();
        assert!(e.contains(&format!("test.toml, line {line}")), "{e}");
        for f in fragments {
            assert!(e.contains(f), "{f} in {e}");
        }
    }
    // Vents and inflators need time.
    assert_error(
        &format!(
            "{sphere}[[cavity]]\ngas = \"adiabatic\"\n{}\n[analysis]\nkind = \"static\"\n",
            inflator.replace("-2.0", "2.0")
        ),
        12,
        "cavity[0].inflator",
        &["needs a dynamic analysis"],
    );
}

/// Woodbury's correction works on every linear path: the balloon of
/// `balloon_radius_matches_the_thin_sphere` solved with `linear =
/// "direct"` (the node-block LU), `"iterative"` (multigrid CG, the extra
/// right-hand sides solved again by CG) and `"reuse"` (a kept factor)
/// reaches the same volume to Newton's tolerance, and with the projected
/// Newton always on (`projection = "progressive"`) too. Without the
/// rank-one part the Newton direction misses the gas's stiffness; the
/// iterations show it: each path converges in a handful.
#[test]
fn the_gas_tangent_works_on_every_linear_path() {
    let base = r#"
[mesh]
shape = "sphere"
radius = 0.1
subdivisions = 2
order = 2
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 1000.0
thickness = 5.0e-4
[[cavity]]
gas = "adiabatic"
mass = 8.94e-3
[[fix]]
at = [0.0, 0.0, 0.1]
[[fix]]
at = [0.0, 0.0, -0.1]
components = ["x", "y"]
[[fix]]
at = [0.1, 0.0, 0.0]
components = ["y"]
[analysis]
kind = "static"
steps = 1
"#;
    let mut volumes = Vec::new();
    for solver in [
        "linear = \"direct\"",
        "linear = \"iterative\"",
        "linear = \"reuse\"",
        "projection = \"progressive\"",
    ] {
        let s = setup(&format!("{base}[solver]\n{solver}\ntolerance = 1e-10\n"));
        let dir = temp_dir("balloon-paths");
        let summary = run(&s, &dir, &mut |_| {}).unwrap();
        assert!(
            summary.newton_iterations <= 10,
            "{solver}: {} iterations",
            summary.newton_iterations
        );
        println!(
            "{solver}: {} Newton iterations, {:?}",
            summary.newton_iterations, summary.linear
        );
        if solver.contains("iterative") {
            assert!(summary.linear.krylov_iterations > 0, "{solver}: no Krylov");
        }
        volumes.push((solver, summary.cavities[0].volume));
    }
    let v0 = volumes[0].1;
    for (solver, v) in &volumes {
        assert!((v / v0 - 1.0).abs() < 1e-8, "{solver}: {v} vs {v0}");
    }
}

/// A run with an inflator and a vent, stopped (as by Ctrl-C) while the
/// bag fills and resumed, ends with the same history bytes as the run
/// that was not stopped: the checkpoint (version 9) carries the gas —
/// mass, temperature, volume, pressure and the flows since the start.
#[test]
fn an_inflating_bag_resumes_bit_for_bit() {
    let text = r#"
[mesh]
shape = "sphere"
radius = 0.1
subdivisions = 2
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 500.0
thickness = 5.0e-4
[[cavity]]
gas = "adiabatic"
inflator = { mass_flow = [[0.0, 0.0], [0.02, 0.05], [0.06, 0.05], [0.08, 0.0]], temperature = 600.0, cp = 1040.0, cv = 743.0 }
[[cavity.vent]]
area = 2.0e-4
[[fix]]
at = [0.0, 0.0, -0.1]
[time]
beta = 1.0
gamma = 1.5
segments = [{ steps = 30, dt = 2.0e-3 }]
[output]
every = 10
"#;
    let dir = temp_dir("bag-resume");
    let path = dir.join("bag.toml");
    std::fs::write(&path, text).unwrap();
    common::stops_and_resumes_bit_for_bit(&path, &dir, 17, |ck| {
        assert_eq!(ck.state.gas.len(), 1);
        assert!(ck.state.gas[0].inflow > 0.0, "{:?}", ck.state.gas[0]);
    });
}

/// Two square plies of 20 cm joined at their rim, lying flat on each
/// other (an OBJ of `n x n` squares a ply: the rim's nodes shared, the
/// inner ones doubled, the lower ply's triangles turned over so that both
/// normals point out), the corner squares cut along the other diagonal
/// so that no triangle has all three corners on the rim (it would be the
/// same triangle in both plies).
fn flat_bag_obj(n: usize, half: f64) -> String {
    let mut ids = std::collections::HashMap::new();
    let mut vertices = String::new();
    let mut faces = String::new();
    let mut node = |i: usize, j: usize, ply: usize, vertices: &mut String| {
        let rim = i == 0 || j == 0 || i == n || j == n;
        let key = (i, j, if rim { 0 } else { ply });
        let next = ids.len() + 1;
        *ids.entry(key).or_insert_with(|| {
            let (x, y) = (
                -half + 2.0 * half * i as f64 / n as f64,
                -half + 2.0 * half * j as f64 / n as f64,
            );
            vertices.push_str(&format!("v {x} {y} 0\n"));
            next
        })
    };
    for ply in 0..2 {
        for i in 0..n {
            for j in 0..n {
                let a = node(i, j, ply, &mut vertices);
                let b = node(i + 1, j, ply, &mut vertices);
                let c = node(i + 1, j + 1, ply, &mut vertices);
                let d = node(i, j + 1, ply, &mut vertices);
                let corner = (i, j) == (0, n - 1) || (i, j) == (n - 1, 0);
                let triangles = if corner {
                    [[a, b, d], [b, c, d]]
                } else {
                    [[a, b, c], [a, c, d]]
                };
                for [p, q, r] in triangles {
                    let (q, r) = if ply == 0 { (q, r) } else { (r, q) };
                    faces.push_str(&format!("f {p} {q} {r}\n"));
                }
            }
        }
    }
    vertices + &faces
}

/// The issue's must-show: an inflator (Wang–Nefske, 600 K) fills an
/// initially flat bag — two plies lying on each other, no volume but the
/// inflator's 10 cm³ chamber — through 80 ms, a vent letting gas out.
/// The bag opens to more than a hundred times its start (a tension
/// field takes the plies' wrinkles), the mass balance `m = m_0 + inflow
/// − outflow` holds at every step to 1e-9 relative, and the pressure
/// never falls below ambient.
#[test]
fn an_inflator_fills_an_initially_flat_bag_with_a_vent() {
    let dir = temp_dir("flat-bag");
    std::fs::write(dir.join("bag.obj"), flat_bag_obj(12, 0.1)).unwrap();
    let text = r#"
[mesh]
shape = "file"
path = "bag.obj"
[material]
youngs_modulus = 1.0e6
poisson_ratio = 0.3
density = 500.0
thickness = 5.0e-4
wrinkling = "relaxed-energy"
[[cavity]]
gas = "adiabatic"
chamber = 1.0e-5
inflator = { mass_flow = [[0.0, 0.0], [0.01, 0.02], [0.05, 0.02], [0.06, 0.0]], temperature = 600.0, cp = 1040.0, cv = 743.0 }
[[cavity.vent]]
area = 1.0e-4
[time]
beta = 1.0
gamma = 1.5
segments = [{ steps = 80, dt = 1.0e-3 }]
[output]
every = 1000
"#;
    let path = dir.join("bag.toml");
    std::fs::write(&path, text).unwrap();
    let (scenario, source) = drape::scenario::Scenario::read(&path).unwrap();
    let s = scenario.build(&path, &source).unwrap();
    let out = dir.join("out");
    run(&s, &out, &mut |_| {}).unwrap();
    let (header, rows) = read_history(&out);
    let v = column(&header, &rows, "cavity0_volume");
    let m = column(&header, &rows, "cavity0_mass");
    let inflow = column(&header, &rows, "cavity0_inflow");
    let outflow = column(&header, &rows, "cavity0_outflow");
    let p = column(&header, &rows, "cavity0_pressure");
    for k in 0..rows.len() {
        let balance = m[0] + inflow[k] - outflow[k];
        assert!(
            (m[k] - balance).abs() <= 1e-9 * m[k],
            "step {k}: {} vs {balance}",
            m[k]
        );
        assert!(p[k] >= AMBIENT * (1.0 - 1e-12), "step {k}: {}", p[k]);
    }
    let last = rows.len() - 1;
    println!(
        "flat bag: V {} -> {} m^3, {} kg in, {} kg out, p {} Pa",
        v[0], v[last], inflow[last], outflow[last], p[last]
    );
    assert!(v[last] > 100.0 * v[0], "the bag opened to {} m^3", v[last]);
    assert!(outflow[last] > 0.0 && (inflow[last] - 1e-3).abs() < 1e-12);
}

/// The issue's folded deployment (examples/folded-bag.toml): the two-ply
/// bag of scripts/meshes/folded_bag.py folded in half, filled by an
/// isothermal inflator (1.5 g over 60 ms) with self-contact on, reaches
/// at t = 0.12 s the volume of the same bag filled from flat with the
/// same gas within 1 % (measured: 0.06 %; an isothermal gas's end state
/// does not depend on the path, an adiabatic one's would), and no edge
/// of it passes through a triangle after any step.
#[test]
fn a_folded_bag_deploys_to_the_flat_bags_volume_without_crossing() {
    let example = include_str!("../../../examples/folded-bag.toml");
    let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/meshes/");
    let volume_at_end = |mesh: &str| {
        let text = example.replace(
            "path = \"meshes/folded-bag.obj\"",
            &format!("path = \"{meshes}{mesh}\""),
        );
        assert_ne!(text, example);
        let (crossings, y, steps, _, _) = drive_through(&text, 0.12, None);
        let s = setup(&text);
        let v = s.model.cavities()[0].surface.volume(&y);
        (v, crossings, steps)
    };
    let (folded, crossings, steps) = volume_at_end("folded-bag.obj");
    let (flat, _, _) = volume_at_end("flat-bag.obj");
    println!("folded bag: {folded} m^3 after {steps} steps, flat: {flat} m^3");
    assert!(steps >= 120);
    assert_eq!(crossings.iter().max(), Some(&0), "crossings: {crossings:?}");
    assert!((folded / flat - 1.0).abs() < 0.01, "{folded} vs {flat}");
    // Deployed: a hundred times the folded bag's initial volume.
    assert!(folded > 0.001, "{folded}");
}

/// A cavity without `pieces` takes the whole mesh: an open disc is
/// refused at the `[[cavity]]` header's line; with `origin` on the
/// disc's plane and its rim held it is closed by that plane, and the
/// rim held only in x and y (free to leave the plane) is refused naming
/// a rim node.
#[test]
fn an_open_surface_is_closed_by_a_plane_through_the_origin_only_where_held() {
    let disc = "[mesh]\nshape = \"disc\"\nradius = 0.1\nrings = 3\n\
        [material]\nyoungs_modulus = 1.0e6\npoisson_ratio = 0.3\ndensity = 500.0\nthickness = 5.0e-4\n";
    assert_error(
        &format!("{disc}[[cavity]]\ngas = \"isothermal\"\nchamber = 1.0e-3\n"),
        10,
        "cavity[0].pieces",
        &["(none given: every triangle of the mesh)", "is not closed"],
    );
    let closed = format!(
        "{disc}[[cavity]]\ngas = \"isothermal\"\norigin = [0.0, 0.0, 0.0]\nchamber = 1.0e-3\n[[fix]]\nboundary = true\n[analysis]\nkind = \"static\"\n"
    );
    let s = build(&closed, Path::new("test.toml")).unwrap();
    let v = s.model.cavities()[0]
        .surface
        .volume(&s.model.initial_positions());
    assert!((v - 1.0e-3).abs() < 1e-15, "a flat disc on its plane: {v}");
    assert_error(
        &closed.replace(
            "boundary = true\n",
            "boundary = true\ncomponents = [\"x\", \"y\"]\n",
        ),
        10,
        "cavity[0].pieces",
        &["neither held in all three components nor held on a symmetry plane"],
    );
}
