//! The gas in a cavity (docs/theory.md §1.16): an ideal gas, `p V = m R
//! T`, isothermal or adiabatic, fed by an inflator and emptied through
//! vents (a control volume as LS-DYNA's `*AIRBAG_WANG_NEFSKE`).
//!
//! A step is split in two. First, explicitly over the step from the
//! converged state `n` at the volume `V_n`, the mass and energy that flow:
//!
//! ```text
//! m_in  = integral_{t_n}^{t_{n+1}} mdot_in dt        (the inflator's table, exact)
//! m_out = dt sum_vents mdot_vent(p_n, T_n)           (isentropic orifice, below)
//! m*    = m_n + m_in - m_out
//! U*    = m_n c_v T_n + m_in c_p,in T_in - m_out c_p T_n       (Wang & Nefske 1988)
//! ```
//!
//! (`m_out` is cut so that the vents never take the pressure at `V_n`
//! below ambient). Then, implicitly, the fixed gas `m*` follows the
//! fabric over the step: isothermal, `p V = m* R T_n`; adiabatic, `p V^gamma
//! = K` with `K = p* V_n^gamma`, `p* = (gamma - 1) U* / V_n`. Within
//! Newton's iterations the gas is then a potential of `V` alone,
//!
//! ```text
//! E(V) = -m* R T ln V                (isothermal: the free energy)
//! E(V) = K V^(1 - gamma) / (gamma - 1) = p V / (gamma - 1)   (adiabatic: U)
//! ```
//!
//! with `-dE/dV = p`; the step's term adds `E(V) + p_amb V`, whose
//! gradient is `-(p - p_amb) dV/dY`, the follower pressure's net force.
//! The gas's work on the fabric over the step is `E(V_n) - E(V_{n+1}) -
//! p_amb (V_{n+1} - V_n)` of the step's law: exact for the split, and the
//! energy the run's balance counts as external work.
//!
//! The vents' flow (Bernoulli for an isentropic expansion from the cavity
//! at `p`, `T` to ambient `p_a`; `C_d` the discharge coefficient, `A` the
//! area, `r = p_a / p`):
//!
//! ```text
//! mdot = C_d A p sqrt(2 gamma / ((gamma - 1) R T) (r^(2/gamma) - r^((gamma+1)/gamma)))
//!                                         r > r_c = (2 / (gamma + 1))^(gamma / (gamma - 1))
//! mdot = C_d A p sqrt(gamma / (R T)) (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1)))
//!                                         r <= r_c (choked)
//! ```
//!
//! and none when `p <= p_a` (a vent lets no air in).

/// How the gas's pressure follows its volume within a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GasLaw {
    /// `p V = m R T` at a fixed temperature (heat flows as needed).
    Isothermal,
    /// `p V^gamma` constant (no heat flows).
    Adiabatic,
}

/// A gas source: a mass flow rate over time and the gas's temperature and
/// heat capacities.
#[derive(Debug, Clone, PartialEq)]
pub struct Inflator {
    /// `(t, mdot)` points (s, kg/s), times increasing, rates >= 0: the rate
    /// is linear between points and holds its end values outside them.
    pub mass_flow: Vec<[f64; 2]>,
    /// The incoming gas's temperature `T_in` (K).
    pub temperature: f64,
    /// Its specific heat at constant pressure `c_p` (J/(kg K)).
    pub cp: f64,
    /// Its specific heat at constant volume `c_v` (J/(kg K)).
    pub cv: f64,
}

impl Inflator {
    /// The rate at time `t` (kg/s).
    pub fn rate(&self, t: f64) -> f64 {
        let table = &self.mass_flow;
        let (Some(first), Some(last)) = (table.first(), table.last()) else {
            return 0.0;
        };
        if t <= first[0] {
            return first[1];
        }
        if t >= last[0] {
            return last[1];
        }
        let k = table.partition_point(|p| p[0] <= t);
        let ([t0, r0], [t1, r1]) = (table[k - 1], table[k]);
        r0 + (r1 - r0) * (t - t0) / (t1 - t0)
    }

    /// The mass it delivers between `t0` and `t1 >= t0` (kg): the exact
    /// integral of the piecewise linear rate (trapezoids between the
    /// table's times that fall inside).
    pub fn mass_between(&self, t0: f64, t1: f64) -> f64 {
        let mut cuts = vec![t0];
        cuts.extend(
            self.mass_flow
                .iter()
                .map(|p| p[0])
                .filter(|&t| t > t0 && t < t1),
        );
        cuts.push(t1);
        cuts.windows(2)
            .map(|w| 0.5 * (self.rate(w[0]) + self.rate(w[1])) * (w[1] - w[0]))
            .sum()
    }
}

/// An orifice to ambient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vent {
    /// Area `A` (m^2).
    pub area: f64,
    /// Discharge coefficient `C_d`, in `(0, 1]`.
    pub discharge: f64,
}

/// A cavity's gas: its law, its constants, what feeds and empties it.
#[derive(Debug, Clone, PartialEq)]
pub struct Gas {
    /// Isothermal or adiabatic.
    pub law: GasLaw,
    /// `gamma = c_p / c_v` (> 1): the adiabatic exponent, and the vents'.
    pub gamma: f64,
    /// The specific gas constant `R = c_p - c_v` (J/(kg K)).
    pub gas_constant: f64,
    /// Ambient pressure `p_amb` (Pa, absolute).
    pub ambient: f64,
    /// The inflator, if any.
    pub inflator: Option<Inflator>,
    /// The vents.
    pub vents: Vec<Vent>,
}

/// The gas of a cavity at a converged state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasState {
    /// Mass `m` (kg).
    pub mass: f64,
    /// Temperature `T` (K).
    pub temperature: f64,
    /// The cavity's volume `V` (m^3).
    pub volume: f64,
    /// Absolute pressure `p = m R T / V` (Pa).
    pub pressure: f64,
    /// Mass the inflator has delivered since the start (kg).
    pub inflow: f64,
    /// Mass the vents have let out since the start (kg).
    pub outflow: f64,
}

/// The gas's pressure as a function of the volume over one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepLaw {
    /// `p = c / V`, `c = m R T` (J).
    Isothermal {
        /// `m R T` (J).
        c: f64,
    },
    /// `p = K V^-gamma`.
    Adiabatic {
        /// `K` (Pa m^(3 gamma)).
        k: f64,
        /// `gamma`.
        gamma: f64,
    },
}

impl StepLaw {
    /// `p(V)` (Pa).
    pub fn pressure(&self, v: f64) -> f64 {
        match *self {
            StepLaw::Isothermal { c } => c / v,
            StepLaw::Adiabatic { k, gamma } => k * v.powf(-gamma),
        }
    }

    /// `-dp/dV` (Pa/m^3), > 0.
    pub fn stiffness(&self, v: f64) -> f64 {
        match *self {
            StepLaw::Isothermal { c } => c / (v * v),
            StepLaw::Adiabatic { gamma, .. } => gamma * self.pressure(v) / v,
        }
    }

    /// `E(V)` (J), `-dE/dV = p`; infinite for `V <= 0`.
    pub fn energy(&self, v: f64) -> f64 {
        if v <= 0.0 {
            return f64::INFINITY;
        }
        match *self {
            StepLaw::Isothermal { c } => -c * v.ln(),
            StepLaw::Adiabatic { gamma, .. } => self.pressure(v) * v / (gamma - 1.0),
        }
    }
}

/// One step of a cavity's gas: its law within the step and what flowed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasStep {
    /// The pressure's law over the step.
    pub law: StepLaw,
    /// Ambient pressure (Pa).
    pub ambient: f64,
    /// The mass over the step `m*` (kg).
    pub mass: f64,
    /// The volume at the step's start (m^3).
    pub start_volume: f64,
    /// The temperature of an isothermal gas (K).
    pub temperature: f64,
    /// Inflow and outflow since the start, at the step's end (kg).
    pub inflow: f64,
    /// See `inflow`.
    pub outflow: f64,
}

impl GasStep {
    /// The energy the step's term adds: `E(V) + p_amb V` (J).
    pub fn potential(&self, v: f64) -> f64 {
        self.law.energy(v) + self.ambient * v
    }

    /// The work the gas does on the fabric from the step's start to the
    /// volume `v`, net of ambient (J).
    pub fn work(&self, v: f64) -> f64 {
        self.potential(self.start_volume) - self.potential(v)
    }
}

impl Gas {
    /// `c_v = R / (gamma - 1)` (J/(kg K)).
    pub fn cv(&self) -> f64 {
        self.gas_constant / (self.gamma - 1.0)
    }

    /// The gas at the start: `mass` (kg) if given, else `pressure` (Pa,
    /// absolute), at `temperature` (K) in `volume` (m^3).
    pub fn initial(
        &self,
        volume: f64,
        pressure: f64,
        mass: Option<f64>,
        temperature: f64,
    ) -> GasState {
        let mass = mass.unwrap_or(pressure * volume / (self.gas_constant * temperature));
        GasState {
            mass,
            temperature,
            volume,
            pressure: mass * self.gas_constant * temperature / volume,
            inflow: 0.0,
            outflow: 0.0,
        }
    }

    /// The vents' outflow rate (kg/s) at `p`, `T` (module docs).
    pub fn vent_rate(&self, p: f64, temperature: f64) -> f64 {
        if p <= self.ambient || self.vents.is_empty() {
            return 0.0;
        }
        let g = self.gamma;
        let rt = self.gas_constant * temperature;
        let r = self.ambient / p;
        let critical = (2.0 / (g + 1.0)).powf(g / (g - 1.0));
        let per_area = if r <= critical {
            p * (g / rt).sqrt() * (2.0 / (g + 1.0)).powf((g + 1.0) / (2.0 * (g - 1.0)))
        } else {
            let bracket = r.powf(2.0 / g) - r.powf((g + 1.0) / g);
            p * (2.0 * g / ((g - 1.0) * rt) * bracket.max(0.0)).sqrt()
        };
        self.vents
            .iter()
            .map(|v| v.discharge * v.area * per_area)
            .sum()
    }

    /// The step from `state` over `[t0, t1]`: the mass and energy that
    /// flow, explicitly (module docs), and the law the gas follows over it.
    pub fn begin_step(&self, state: &GasState, t0: f64, t1: f64) -> GasStep {
        let (m, t, v) = (state.mass, state.temperature, state.volume);
        let cv = self.cv();
        let cp = self.gamma * cv;
        let (m_in, h_in) = match &self.inflator {
            Some(inflator) => {
                let m_in = inflator.mass_between(t0, t1);
                (m_in, m_in * inflator.cp * inflator.temperature)
            }
            None => (0.0, 0.0),
        };
        let u = m * cv * t;
        let mut m_out = (t1 - t0) * self.vent_rate(state.pressure, t);
        // The vents stop at ambient pressure (at V_n): at most what leaves
        // p* = p_amb.
        let most = match self.law {
            GasLaw::Isothermal => m + m_in - self.ambient * v / (self.gas_constant * t),
            GasLaw::Adiabatic => (u + h_in - self.ambient * v / (self.gamma - 1.0)) / (cp * t),
        };
        m_out = m_out.min(most.max(0.0));
        let mass = m + m_in - m_out;
        let law = match self.law {
            GasLaw::Isothermal => StepLaw::Isothermal {
                c: mass * self.gas_constant * t,
            },
            GasLaw::Adiabatic => {
                let u_star = u + h_in - m_out * cp * t;
                let p_star = (self.gamma - 1.0) * u_star / v;
                StepLaw::Adiabatic {
                    k: p_star * v.powf(self.gamma),
                    gamma: self.gamma,
                }
            }
        };
        GasStep {
            law,
            ambient: self.ambient,
            mass,
            start_volume: v,
            temperature: t,
            inflow: state.inflow + m_in,
            outflow: state.outflow + m_out,
        }
    }

    /// The converged state at the end of `step`, where the cavity's volume
    /// is `volume`.
    pub fn end_step(&self, step: &GasStep, volume: f64) -> GasState {
        let pressure = step.law.pressure(volume);
        let temperature = match self.law {
            GasLaw::Isothermal => step.temperature,
            GasLaw::Adiabatic => pressure * volume / (step.mass * self.gas_constant),
        };
        GasState {
            mass: step.mass,
            temperature,
            volume,
            pressure,
            inflow: step.inflow,
            outflow: step.outflow,
        }
    }
}

/// The gas at the start of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialGas {
    /// Absolute pressure (Pa), unless `mass` is given.
    pub pressure: f64,
    /// Mass (kg), if given instead of the pressure.
    pub mass: Option<f64>,
    /// Temperature (K).
    pub temperature: f64,
}

/// A cavity of the fabric and the gas in it.
#[derive(Debug, Clone)]
pub struct GasCavity {
    /// The surface that encloses it.
    pub surface: super::cavity::Cavity,
    /// The gas.
    pub gas: Gas,
    /// The gas at the start.
    pub initial: InitialGas,
}

impl GasCavity {
    /// The gas's state at positions `y` at the start of a run.
    pub fn initial_state(&self, y: &[f64]) -> GasState {
        let i = self.initial;
        self.gas
            .initial(self.surface.volume(y), i.pressure, i.mass, i.temperature)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air(law: GasLaw) -> Gas {
        Gas {
            law,
            gamma: 1.4,
            gas_constant: 287.0,
            ambient: 101_325.0,
            inflator: None,
            vents: Vec::new(),
        }
    }

    /// `-dE/dV = p` and `-dp/dV` = the stiffness, by central differences,
    /// for both laws.
    #[test]
    fn the_step_laws_derivatives_match_finite_differences() {
        for law in [
            StepLaw::Isothermal { c: 250.0 },
            StepLaw::Adiabatic {
                k: 3.0e3,
                gamma: 1.3,
            },
        ] {
            let v = 2.3e-3;
            let h = 1e-6 * v;
            let p_fd = -(law.energy(v + h) - law.energy(v - h)) / (2.0 * h);
            let k_fd = -(law.pressure(v + h) - law.pressure(v - h)) / (2.0 * h);
            // Central differences: O(h^2) truncation, round-off eps E / h.
            assert!((p_fd / law.pressure(v) - 1.0).abs() < 1e-7, "{law:?}");
            assert!((k_fd / law.stiffness(v) - 1.0).abs() < 1e-7, "{law:?}");
            assert_eq!(law.energy(0.0), f64::INFINITY);
        }
    }

    /// The inflator's mass between two times is the integral of its
    /// piecewise linear table: over the whole table the trapezoids' sum,
    /// and additive over any split.
    #[test]
    fn inflator_mass_is_the_tables_integral() {
        let inflator = Inflator {
            mass_flow: vec![[0.0, 0.0], [0.01, 2.0], [0.03, 1.0], [0.04, 0.0]],
            temperature: 600.0,
            cp: 1040.0,
            cv: 743.0,
        };
        let whole = 0.5 * 2.0 * 0.01 + 0.5 * 3.0 * 0.02 + 0.5 * 1.0 * 0.01;
        assert!((inflator.mass_between(0.0, 0.05) - whole).abs() < 1e-15);
        let split = inflator.mass_between(0.0, 0.013) + inflator.mass_between(0.013, 0.05);
        assert!((split - whole).abs() < 1e-15);
        assert_eq!(inflator.rate(0.02), 1.5);
    }

    /// A vent chokes below the critical pressure ratio and its two
    /// formulas meet there; the flow is continuous and grows with `p`.
    #[test]
    fn vent_flow_is_continuous_at_the_choke() {
        let mut gas = air(GasLaw::Adiabatic);
        gas.vents.push(Vent {
            area: 1e-4,
            discharge: 0.6,
        });
        let critical = (2.0f64 / 2.4).powf(1.4 / 0.4);
        let p_c = gas.ambient / critical;
        let below = gas.vent_rate(p_c * (1.0 - 1e-9), 300.0);
        let above = gas.vent_rate(p_c * (1.0 + 1e-9), 300.0);
        assert!((above / below - 1.0).abs() < 1e-6);
        assert_eq!(gas.vent_rate(gas.ambient, 300.0), 0.0);
        assert!(gas.vent_rate(1.2e5, 300.0) < gas.vent_rate(1.5e5, 300.0));
    }

    /// Without flows an adiabatic step keeps `p V^gamma`, an isothermal
    /// one `p V`, and the work is minus the change of the potential.
    #[test]
    fn closed_gas_keeps_its_invariant() {
        for law in [GasLaw::Isothermal, GasLaw::Adiabatic] {
            let gas = air(law);
            let s0 = gas.initial(1e-3, 1.5e5, None, 300.0);
            let step = gas.begin_step(&s0, 0.0, 0.1);
            let s1 = gas.end_step(&step, 0.8e-3);
            let (a, b) = match law {
                GasLaw::Isothermal => (s0.pressure * s0.volume, s1.pressure * s1.volume),
                GasLaw::Adiabatic => (
                    s0.pressure * s0.volume.powf(1.4),
                    s1.pressure * s1.volume.powf(1.4),
                ),
            };
            assert!((a / b - 1.0).abs() < 1e-14, "{law:?}");
            assert_eq!(s1.mass, s0.mass);
            // Compressed: the gas did negative work on the fabric.
            assert!(step.work(0.8e-3) < 0.0);
        }
    }
}
