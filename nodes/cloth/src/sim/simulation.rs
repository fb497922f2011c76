//! A whole simulation: every flame's state stepped frame by frame, and the check of its sub-step
//! against the stability limit of its topology.

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::AnimError;
use rayon::prelude::*;

use super::cloth_params::ClothParams;
use super::error::ClothError;
use super::model::{FlameState, Topology, mix, unit_random, wind_active};
use crate::state::ClothState;

/// A whole simulation: shared topology, every flame's state and the frame it has reached.
#[derive(Clone, Debug)]
pub struct Simulation {
    topo: Arc<Topology>,
    pub(super) params: ClothParams,
    roots: Vec<Vec3>,
    flames: Vec<FlameState>,
    frame: usize,
}

impl Simulation {
    /// Flames at rest at `roots`, each with its own phase, wind strength and seed drawn from
    /// `params.seed`. Validates the parameters and the step.
    pub fn new(params: &ClothParams, roots: &[Vec3]) -> Result<Self, ClothError> {
        params.validate()?;
        let topo = Topology::grid(params);
        check_step(&topo, params)?;
        let period = params.wind_on + params.wind_off;
        let flames = (0..roots.len())
            .map(|i| {
                let phase = unit_random(params.seed, i, 1) * period;
                let jitter = params.wind_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(params.seed, i, 2) - 1.0);
                FlameState::at_rest(&topo, phase, 1.0 + jitter, mix(params.seed, i, 3) as u32)
            })
            .collect();
        Ok(Simulation { topo: Arc::new(topo), params: params.clone(), roots: roots.to_vec(), flames, frame: 0 })
    }

    /// The frame the simulation has reached.
    pub fn frame(&self) -> usize {
        self.frame
    }

    /// The shared topology.
    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// The flames.
    pub fn flames(&self) -> &[FlameState] {
        &self.flames
    }

    /// Sub-steps per frame and their length: `ceil((1/fps) / dt)` equal steps.
    pub fn substeps(&self) -> (usize, f32) {
        let frame_dt = 1.0 / self.params.fps as f64;
        let n = (frame_dt / self.params.dt as f64).ceil().max(1.0) as usize;
        (n, (frame_dt / n as f64) as f32)
    }

    /// Advances every flame by `steps` sub-steps of length `h` (flames in parallel), without
    /// changing the frame counter; for benchmarks of raw stepping.
    pub fn substep(&mut self, h: f32, steps: usize) {
        self.advance_flames(h, steps, None);
    }

    /// The buoyancy and wind at each of the next `steps` sub-steps of length `h`, sampled at the
    /// sub-step's start, when either is animated (`None` when both are constant).
    fn sampled_forces(&self, h: f32, steps: usize) -> Result<Option<Vec<(f32, Vec3)>>, AnimError> {
        let p = &self.params;
        if !p.buoyancy.is_animated() && !p.wind.is_animated() {
            return Ok(None);
        }
        let fps = f64::from(p.fps);
        (0..steps)
            .map(|k| {
                let frame = self.frame as f64 + k as f64 * f64::from(h) * fps;
                Ok((p.buoyancy.at(frame, fps)?, Vec3::from_array(p.wind.at(frame, fps)?)))
            })
            .collect::<Result<Vec<_>, AnimError>>()
            .map(Some)
    }

    /// Advances every flame by `steps` sub-steps of length `h`, each flame all its sub-steps at
    /// once while its masses are in cache; flames in parallel chunks when there is enough work.
    /// Returns the first flame whose state is no longer finite.
    fn advance_flames(&mut self, h: f32, steps: usize, forces: Option<&[(f32, Vec3)]>) -> Option<usize> {
        let t0 = self.frame as f64 / self.params.fps as f64;
        let (topo, p) = (&*self.topo, &self.params);
        let work = |(i, f): (usize, &mut FlameState)| {
            let ext = external(p, f.phase, f.wind_scale, forces.map(|s| (s, t0, h)));
            if f.advance_checked(topo, p.mass, p.drag, h, steps, t0, ext) { usize::MAX } else { i }
        };
        let flames = self.flames.len();
        let first_bad = if flames.saturating_mul(topo.masses()).saturating_mul(steps) < PARALLEL_WORK {
            self.flames.iter_mut().enumerate().map(work).min()
        } else {
            let chunk = flames.div_ceil(4 * rayon::current_num_threads().max(1)).max(1);
            self.flames.par_iter_mut().enumerate().with_min_len(chunk).map(work).min()
        };
        first_bad.filter(|&i| i != usize::MAX)
    }

    /// Advances one frame (all its sub-steps, flames in parallel). A diverged simulation is an
    /// error naming `dt`, never a NaN frame.
    pub fn step_frame(&mut self) -> Result<(), ClothError> {
        let (n, h) = self.substeps();
        let forces = self.sampled_forces(h, n)?;
        let bad = self.advance_flames(h, n, forces.as_deref());
        self.frame += 1;
        if let Some(i) = bad {
            return Err(ClothError::new(
                ClothParams::dt_port(),
                format!("flame {i} diverged at frame {} (positions not finite); lower dt or the stiffness", self.frame),
            ));
        }
        Ok(())
    }

    /// The current state as a port value.
    pub fn snapshot(&self) -> ClothState {
        let n = self.topo.masses();
        let mut positions = Vec::with_capacity(n * self.flames.len());
        for f in &self.flames {
            positions.extend((0..n).map(|i| [f.pos[0][i], f.pos[1][i], f.pos[2][i]]));
        }
        ClothState {
            width: self.params.grid_width as u32,
            height: self.params.grid_height as u32,
            roots: self.roots.iter().map(|r| r.to_array()).collect(),
            seeds: self.flames.iter().map(|f| f.seed).collect(),
            positions,
            time: (self.frame as f64 / self.params.fps as f64) as f32,
        }
    }

    pub(super) fn bytes(&self) -> usize {
        self.flames.len() * self.topo.masses() * 24 + 64
    }
}

/// Checks `p.dt` against the stability limit of [`Topology::stable_step`].
pub fn check_step(topo: &Topology, p: &ClothParams) -> Result<(), ClothError> {
    let limit = topo.stable_step(p.mass, p.drag);
    if p.dt.is_nan() || p.dt >= limit {
        return Err(ClothError::new(
            ClothParams::dt_port(),
            format!(
                "a sub-step of {} s would blow up: semi-implicit Euler is stable only below {limit:.6} s for mass {} \
                 and springs up to k = {} (≈ 2·√(m/k_eff)); lower dt, raise mass or lower the stiffness",
                p.dt,
                p.mass,
                p.stiffness.max(p.shear_stiffness).max(p.bend_stiffness)
            ),
        ));
    }
    Ok(())
}

/// Mass-steps (flames × masses × sub-steps) below which a call steps its flames on one thread:
/// less work than this does not pay for waking the pool.
const PARALLEL_WORK: usize = 16_384;

/// Sub-step samples of an animated buoyancy and wind: the samples, the first sub-step's time
/// (seconds) and the sub-step length.
type Sampled<'a> = (&'a [(f32, Vec3)], f64, f32);

/// The external force on every mass of a flame at time `t`: buoyancy, plus the flame's wind
/// while an impulse is on (§External Forces). With `sampled`, the buoyancy and wind are those
/// sampled for the sub-step starting at `t`.
fn external<'a>(p: &ClothParams, phase: f32, wind_scale: f32, sampled: Option<Sampled<'a>>) -> impl Fn(f64) -> Vec3 + use<'a> {
    let (up, wind) = (Vec3::Y * *p.buoyancy.value(), Vec3::from_array(*p.wind.value()));
    let (on, off) = (p.wind_on, p.wind_off);
    move |t| {
        let (up, wind) = match sampled {
            Some((s, t0, h)) => {
                let k = (((t - t0) / f64::from(h)).round().max(0.0) as usize).min(s.len() - 1);
                (Vec3::Y * s[k].0, s[k].1)
            }
            None => (up, wind),
        };
        if wind_active(t, phase, on, off) { up + wind * wind_scale } else { up }
    }
}

/// `count` roots on a square-ish grid in the ground (x–z) plane, `spacing` apart, centred on the origin.
pub fn grid_roots(count: usize, spacing: f32) -> Vec<Vec3> {
    let cols = (count as f64).sqrt().ceil().max(1.0) as usize;
    let rows = count.div_ceil(cols);
    (0..count)
        .map(|i| {
            let (r, c) = (i / cols, i % cols);
            Vec3::new((c as f32 - (cols as f32 - 1.0) / 2.0) * spacing, 0.0, (r as f32 - (rows as f32 - 1.0) / 2.0) * spacing)
        })
        .collect()
}
