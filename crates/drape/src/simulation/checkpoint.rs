//! Checkpoints: the full state of a run in a versioned binary file, to
//! resume from (`drape run --resume DIR`).
//!
//! Format (little-endian), version 3:
//!
//! ```text
//! magic "DRAPECKP" · version u32 · scenario hash u64 · dofs u64 · nodes u64 · bodies u64
//! counters: scheduled steps done, converged steps, Newton iterations, cut-back steps (u64 each),
//!           first contact time f64 (NaN: none), last strain energy f64,
//!           steps since the last frame u64, step of the last frame u64, wall seconds f64,
//!           segment u64, step size f64, still steps u64
//! state: time f64, external work f64, acceleration persistence f64,
//!        positions, velocities, accelerations,
//!        external forces of the last step (dofs f64 each)
//! contact u8 (0/1), then hints (nodes x bodies u32), held (nodes x 2 u32, u32::MAX: none),
//!        multipliers (nodes f64)
//! frames u64, then (time f64, step u64) each
//! FNV-1a of everything before, u64
//! ```
//!
//! Version 1 (drape before the predictor carried the persistence) is read
//! too, without the persistence: it resumes with 1, the predictor it had.
//! Versions 1 and 2 (drape before adaptive steps and the rest criterion)
//! have no segment, step size and still steps: they resume with 0 for each
//! (a fixed schedule's values; adaptive runs did not exist).
//!
//! Every count is checked against the model before anything is allocated,
//! and the trailing hash rejects a truncated or damaged file.

use crate::contact::ContactState;
use crate::integrator::State;
use crate::scenario::fnv1a;
use crate::simulation::schedule::REST_STEPS;

const MAGIC: &[u8; 8] = b"DRAPECKP";
const VERSION: u32 = 3;

/// The run's counters at a checkpoint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Counters {
    /// Scheduled steps completed (each may have been cut into sub-steps).
    pub scheduled_done: usize,
    /// Converged (sub-)steps: history rows after the initial one.
    pub step: usize,
    /// Newton iterations so far.
    pub iterations: usize,
    /// Steps that needed a cut-back.
    pub cutback_steps: usize,
    /// Time of the first step that ended in contact.
    pub first_contact_time: Option<f64>,
    /// Strain energy of the last step (J).
    pub last_strain: f64,
    /// Converged steps since the last frame.
    pub since_frame: usize,
    /// Step of the last frame written.
    pub last_written: usize,
    /// Wall time spent before this point (s).
    pub wall_seconds: f64,
    /// Adaptive steps: the schedule's segment the run is in (0 with fixed
    /// steps).
    pub segment: usize,
    /// Adaptive steps: the controller's step size for the next step (s;
    /// 0 with fixed steps).
    pub step_size: f64,
    /// Rest criterion: consecutive converged steps with every node slower
    /// than the rest speed (0 without a rest criterion), below
    /// [`REST_STEPS`].
    pub still_steps: usize,
}

/// Everything a run needs to continue.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// Hash of the scenario text the run was started with.
    pub scenario_hash: u64,
    /// Counters.
    pub counters: Counters,
    /// The integrator's state.
    pub state: State,
    /// External forces at the end of the last step (the work integral's
    /// left end).
    pub external_forces: Vec<f64>,
    /// Frames written so far: `(time, step)`.
    pub frames: Vec<(f64, usize)>,
}

/// A checkpoint that cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// Reading failed.
    #[error("cannot read the checkpoint: {0}")]
    Io(#[from] std::io::Error),
    /// Not a checkpoint, another version, damaged or truncated.
    #[error("the checkpoint is unusable: {0}")]
    Invalid(String),
    /// The scenario has changed since the checkpoint was written.
    #[error(
        "the scenario has changed since the checkpoint was written (hash {found:016x}, the checkpoint's {expected:016x}): resuming would mix two different problems; start a new run instead"
    )]
    ScenarioChanged {
        /// The checkpoint's.
        expected: u64,
        /// The scenario's now.
        found: u64,
    },
}

impl Checkpoint {
    /// Serialises the checkpoint.
    pub fn to_bytes(&self) -> Vec<u8> {
        let s = &self.state;
        let dofs = s.positions.len();
        let nodes = dofs / 3;
        let bodies = s
            .contact
            .as_ref()
            .map_or(0, |c| c.hints.len() / nodes.max(1));
        let mut b = Vec::with_capacity(64 + 8 * 6 * dofs);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        for v in [self.scenario_hash, dofs as u64, nodes as u64, bodies as u64] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let c = &self.counters;
        for v in [c.scheduled_done, c.step, c.iterations, c.cutback_steps] {
            b.extend_from_slice(&(v as u64).to_le_bytes());
        }
        b.extend_from_slice(&c.first_contact_time.unwrap_or(f64::NAN).to_le_bytes());
        b.extend_from_slice(&c.last_strain.to_le_bytes());
        b.extend_from_slice(&(c.since_frame as u64).to_le_bytes());
        b.extend_from_slice(&(c.last_written as u64).to_le_bytes());
        b.extend_from_slice(&c.wall_seconds.to_le_bytes());
        b.extend_from_slice(&(c.segment as u64).to_le_bytes());
        b.extend_from_slice(&c.step_size.to_le_bytes());
        b.extend_from_slice(&(c.still_steps as u64).to_le_bytes());
        b.extend_from_slice(&s.time.to_le_bytes());
        b.extend_from_slice(&s.external_work.to_le_bytes());
        b.extend_from_slice(&s.persistence.to_le_bytes());
        for v in [
            &s.positions,
            &s.velocities,
            &s.accelerations,
            &self.external_forces,
        ] {
            for x in v.iter() {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        match &s.contact {
            None => b.push(0),
            Some(cs) => {
                b.push(1);
                for h in &cs.hints {
                    b.extend_from_slice(&h.to_le_bytes());
                }
                for held in &cs.active {
                    let (k, f) = held.unwrap_or((u32::MAX, u32::MAX));
                    b.extend_from_slice(&k.to_le_bytes());
                    b.extend_from_slice(&f.to_le_bytes());
                }
                for m in &cs.multipliers {
                    b.extend_from_slice(&m.to_le_bytes());
                }
            }
        }
        b.extend_from_slice(&(self.frames.len() as u64).to_le_bytes());
        for (t, step) in &self.frames {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&(*step as u64).to_le_bytes());
        }
        let hash = fnv1a(&b);
        b.extend_from_slice(&hash.to_le_bytes());
        b
    }

    /// Reads a checkpoint written for a model of `dofs` unknowns and
    /// `bodies` obstacles, by the scenario whose hash is `scenario_hash`.
    pub fn from_bytes(
        bytes: &[u8],
        dofs: usize,
        bodies: usize,
        scenario_hash: u64,
    ) -> Result<Self, CheckpointError> {
        let bad = |m: &str| CheckpointError::Invalid(m.to_string());
        if bytes.len() < 8 + 4 + 32 + 8 || &bytes[..8] != MAGIC {
            return Err(bad("not a drape checkpoint"));
        }
        let (body, tail) = bytes.split_at(bytes.len() - 8);
        let stored = u64::from_le_bytes(tail.try_into().map_err(|_| bad("truncated"))?);
        if fnv1a(body) != stored {
            return Err(bad("damaged or truncated (its checksum does not match)"));
        }
        let mut r = Reader { bytes: body, at: 8 };
        let version = r.u32()?;
        if !(1..=VERSION).contains(&version) {
            return Err(bad(&format!(
                "version {version}, this drape reads versions 1 to {VERSION}"
            )));
        }
        let hash = r.u64()?;
        if hash != scenario_hash {
            return Err(CheckpointError::ScenarioChanged {
                expected: hash,
                found: scenario_hash,
            });
        }
        let (d, nodes, b) = (r.usize()?, r.usize()?, r.usize()?);
        if d != dofs || nodes * 3 != dofs || b != bodies {
            return Err(bad(&format!(
                "written for {d} unknowns and {b} obstacles, the scenario has {dofs} and {bodies}"
            )));
        }
        let mut counters = Counters {
            scheduled_done: r.usize()?,
            step: r.usize()?,
            iterations: r.usize()?,
            cutback_steps: r.usize()?,
            first_contact_time: Some(r.f64()?).filter(|t| !t.is_nan()),
            last_strain: r.f64()?,
            since_frame: r.usize()?,
            last_written: r.usize()?,
            wall_seconds: r.f64()?,
            ..Counters::default()
        };
        if version >= 3 {
            counters.segment = r.usize()?;
            counters.step_size = r.f64()?;
            counters.still_steps = r.usize()?;
        }
        if !(counters.step_size.is_finite() && counters.step_size >= 0.0) {
            return Err(bad(&format!(
                "step size {} is not a finite size >= 0",
                counters.step_size
            )));
        }
        if counters.still_steps >= REST_STEPS {
            return Err(bad(&format!(
                "still steps {} not below {REST_STEPS} (the run would have ended at rest)",
                counters.still_steps
            )));
        }
        let time = r.f64()?;
        let external_work = r.f64()?;
        let persistence = if version >= 2 { r.f64()? } else { 1.0 };
        if !(0.0..=1.0).contains(&persistence) {
            return Err(bad(&format!(
                "acceleration persistence {persistence} outside [0, 1]"
            )));
        }
        let positions = r.f64s(dofs)?;
        let velocities = r.f64s(dofs)?;
        let accelerations = r.f64s(dofs)?;
        let external_forces = r.f64s(dofs)?;
        let contact = match r.u8()? {
            0 => None,
            1 => {
                let hints = (0..nodes * bodies)
                    .map(|_| r.u32())
                    .collect::<Result<_, _>>()?;
                let active = (0..nodes)
                    .map(|_| {
                        let (k, f) = (r.u32()?, r.u32()?);
                        Ok((k != u32::MAX).then_some((k, f)))
                    })
                    .collect::<Result<_, CheckpointError>>()?;
                let multipliers = r.f64s(nodes)?;
                Some(ContactState {
                    hints,
                    active,
                    multipliers,
                })
            }
            _ => return Err(bad("bad contact flag")),
        };
        let count = r.usize()?;
        if count > r.remaining() / 16 {
            return Err(bad("frame count beyond the file"));
        }
        let frames = (0..count)
            .map(|_| Ok((r.f64()?, r.usize()?)))
            .collect::<Result<_, CheckpointError>>()?;
        if r.remaining() != 0 {
            return Err(bad("trailing bytes"));
        }
        Ok(Self {
            scenario_hash: hash,
            counters,
            state: State {
                time,
                positions,
                velocities,
                accelerations,
                persistence,
                external_work,
                contact,
            },
            external_forces,
            frames,
        })
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], CheckpointError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| CheckpointError::Invalid("truncated".into()))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn remaining(&self) -> usize {
        self.bytes.len() - self.at
    }
    fn u8(&mut self) -> Result<u8, CheckpointError> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, CheckpointError> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self) -> Result<u64, CheckpointError> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn usize(&mut self) -> Result<usize, CheckpointError> {
        usize::try_from(self.u64()?).map_err(|_| CheckpointError::Invalid("count too large".into()))
    }
    fn f64(&mut self) -> Result<f64, CheckpointError> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f64s(&mut self, n: usize) -> Result<Vec<f64>, CheckpointError> {
        if n > self.remaining() / 8 {
            return Err(CheckpointError::Invalid("truncated".into()));
        }
        (0..n).map(|_| self.f64()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(contact: bool) -> Checkpoint {
        let n = 6;
        let v = |k: f64| (0..n).map(|i| k + i as f64 * 0.1).collect::<Vec<f64>>();
        Checkpoint {
            scenario_hash: 0xdead_beef,
            counters: Counters {
                scheduled_done: 7,
                step: 9,
                iterations: 21,
                cutback_steps: 1,
                first_contact_time: Some(0.25),
                last_strain: 1e-3,
                since_frame: 2,
                last_written: 7,
                wall_seconds: 0.5,
                segment: 1,
                step_size: 2.5e-3,
                still_steps: 4,
            },
            state: State {
                time: 0.3,
                positions: v(1.0),
                velocities: v(2.0),
                accelerations: v(3.0),
                persistence: 0.375,
                external_work: 0.01,
                contact: contact.then(|| ContactState {
                    hints: vec![0, u32::MAX, 2, 1],
                    active: vec![Some((0, 2)), None],
                    multipliers: vec![0.5, 0.0],
                }),
            },
            external_forces: v(4.0),
            frames: vec![(0.0, 0), (0.2, 5)],
        }
    }

    #[test]
    fn round_trips_bit_for_bit_and_rejects_damage_and_other_scenarios() {
        for contact in [false, true] {
            let c = sample(contact);
            let bytes = c.to_bytes();
            let bodies = usize::from(contact) * 2;
            assert_eq!(
                Checkpoint::from_bytes(&bytes, 6, bodies, 0xdead_beef).unwrap(),
                c
            );
            assert!(matches!(
                Checkpoint::from_bytes(&bytes, 6, bodies, 1),
                Err(CheckpointError::ScenarioChanged { .. })
            ));
            assert!(Checkpoint::from_bytes(&bytes, 9, bodies, 0xdead_beef).is_err());
            for cut in [0, 10, bytes.len() / 2, bytes.len() - 1] {
                assert!(Checkpoint::from_bytes(&bytes[..cut], 6, bodies, 0xdead_beef).is_err());
            }
            let mut flipped = bytes.clone();
            flipped[40] ^= 1;
            assert!(Checkpoint::from_bytes(&flipped, 6, bodies, 0xdead_beef).is_err());
        }
    }

    /// Re-seals `body` (a file without its trailing hash) as `version`.
    fn seal(mut body: Vec<u8>, version: u32) -> Vec<u8> {
        body[8..12].copy_from_slice(&version.to_le_bytes());
        let hash = fnv1a(&body);
        body.extend_from_slice(&hash.to_le_bytes());
        body
    }

    /// The same file as version 2 wrote it (without segment, step size and
    /// still steps) or version 1 (without the persistence too).
    fn as_version(bytes: &[u8], version: u32) -> Vec<u8> {
        // magic, version, 4 header u64, 4 counters u64, 5 counter fields:
        // version 3's segment, step size and still steps follow; then
        // time and external work, and the persistence.
        let counters_end = 8 + 4 + 8 * 4 + 8 * 4 + 8 * 5;
        let persistence = counters_end + 8 * 3 + 8 * 2;
        let mut old = bytes[..counters_end].to_vec();
        let skip = if version == 1 {
            old.extend_from_slice(&bytes[counters_end + 24..persistence]);
            persistence + 8
        } else {
            counters_end + 24
        };
        old.extend_from_slice(&bytes[skip..bytes.len() - 8]);
        seal(old, version)
    }

    /// Versions 1 and 2 resume with 0 for the adaptive steps' segment and
    /// step size and the rest criterion's still steps (a fixed schedule's
    /// values), version 1 with the persistence 1 (the predictor it was
    /// written with).
    #[test]
    fn reads_versions_1_and_2_with_defaults_for_the_new_fields() {
        let c = sample(true);
        let bytes = c.to_bytes();
        let mut expected = c.clone();
        expected.counters.segment = 0;
        expected.counters.step_size = 0.0;
        expected.counters.still_steps = 0;
        let v2 = Checkpoint::from_bytes(&as_version(&bytes, 2), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v2, expected);
        expected.state.persistence = 1.0;
        let v1 = Checkpoint::from_bytes(&as_version(&bytes, 1), 6, 2, 0xdead_beef).unwrap();
        assert_eq!(v1, expected);
    }

    /// Values out of range are refused naming the field: a persistence
    /// outside [0, 1], a step size that is not finite or negative, still
    /// steps that would have ended the run; and a version this drape does
    /// not know.
    #[test]
    fn refuses_values_out_of_range_and_unknown_versions() {
        let refused = |change: &dyn Fn(&mut Checkpoint), says: &str| {
            let mut bad = sample(true);
            change(&mut bad);
            let e = Checkpoint::from_bytes(&bad.to_bytes(), 6, 2, 0xdead_beef).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
        };
        refused(&|c| c.state.persistence = 1.5, "persistence 1.5");
        refused(&|c| c.counters.step_size = f64::NAN, "step size NaN");
        refused(&|c| c.counters.step_size = -1e-3, "step size -0.001");
        refused(&|c| c.counters.step_size = f64::INFINITY, "step size inf");
        refused(&|c| c.counters.still_steps = REST_STEPS, "still steps 10");
        // A later version is refused by name.
        let mut later = sample(true).to_bytes();
        later.truncate(later.len() - 8);
        let later = seal(later, 4);
        let e = Checkpoint::from_bytes(&later, 6, 2, 0xdead_beef).unwrap_err();
        assert!(
            e.to_string()
                .contains("version 4, this drape reads versions 1 to 3"),
            "{e}"
        );
    }
}
