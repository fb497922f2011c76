//! Mass-spring flames (mass-spring flame project 2019 §Integration, §Internal Forces,
//! §External Forces; shear and bend springs after Provot 1995): the grid topology, the per-flame
//! state in structure-of-arrays form, the semi-implicit Euler stepper with sub-steps, its
//! stability limit, and the `cloth.mass_spring_flame` node whose clip is backed by a stepping cache.

use std::collections::{BTreeMap, VecDeque};
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use glam::Vec3;
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{
    Clip, ClothState, CookCtx, FnNode, FrameSource, Inputs, NodeDesc, NodeError, Particles, PortDesc, PortType, Registry,
    TimeDep, Value,
};
use rayon::prelude::*;

use crate::stencil::{self, GridStencil};

/// Adds `cloth.mass_spring_flame`.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(mass_spring_flame_desc(), cook_mass_spring_flame));
}

/// A deterministic uniform number in 0..1 from `(seed, flame, salt)` (SplitMix64).
pub fn unit_random(seed: u32, flame: usize, salt: u64) -> f32 {
    (mix(seed, flame, salt) >> 40) as f32 / (1u64 << 24) as f32
}

fn mix(seed: u32, flame: usize, salt: u64) -> u64 {
    let mut z = (seed as u64) ^ ((flame as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) ^ salt.wrapping_mul(0xD1B5_4A32_D192_ED69);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Every parameter of a mass-spring flame simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothParams {
    /// Masses per row (the project: 16).
    pub grid_width: usize,
    /// Rows of masses (the project: 32); row 0 is pinned.
    pub grid_height: usize,
    /// Rest width of the cloth in world units.
    pub flame_width: f32,
    /// Rest height of the cloth in world units.
    pub flame_height: f32,
    /// Mass of every mass point.
    pub mass: f32,
    /// Spring constant `k` of the structural (horizontal and vertical) springs, Hooke's law.
    pub stiffness: f32,
    /// Damping of every spring along its axis (force per unit relative speed).
    pub damping: f32,
    /// Add diagonal shear springs (Provot 1995).
    pub shear: bool,
    /// Spring constant of the shear springs.
    pub shear_stiffness: f32,
    /// Add bend (flexion) springs spanning two cells (Provot 1995).
    pub bend: bool,
    /// Spring constant of the bend springs.
    pub bend_stiffness: f32,
    /// Air drag: force `−drag·v` on every mass.
    pub drag: f32,
    /// Upward force on every mass (§External Forces: the cloth "falls upwards").
    pub buoyancy: f32,
    /// Wind force on every mass while an impulse is on (flame-local x across, y up, z toward the viewer).
    pub wind: Vec3,
    /// Seconds each wind impulse lasts (the project: 1 s).
    pub wind_on: f32,
    /// Seconds between impulses (the project: 5 s).
    pub wind_off: f32,
    /// Random per-flame variation of the wind strength, 0..1.
    pub wind_jitter: f32,
    /// Longest sub-step in seconds; each frame is split into equal sub-steps no longer than this.
    pub dt: f32,
    /// Frames per second.
    pub fps: f32,
    /// Seed of the per-flame phases, wind strengths and textures.
    pub seed: u32,
}

impl Default for ClothParams {
    fn default() -> Self {
        ClothParams {
            grid_width: 16,
            grid_height: 32,
            flame_width: 1.0,
            flame_height: 2.0,
            mass: 0.005,
            stiffness: 100.0,
            damping: 0.02,
            shear: true,
            shear_stiffness: 30.0,
            bend: true,
            bend_stiffness: 15.0,
            drag: 0.004,
            buoyancy: 0.05,
            wind: Vec3::new(0.03, 0.0, 0.01),
            wind_on: 1.0,
            wind_off: 5.0,
            wind_jitter: 0.3,
            dt: 1.0 / 600.0,
            fps: 24.0,
            seed: 0,
        }
    }
}

/// The springs and masses shared by every flame, as flat arrays (no per-spring objects).
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Whether each mass is pinned (never moves).
    pub pinned: Vec<bool>,
    /// Rest positions, one array per axis.
    pub rest: [Vec<f32>; 3],
    /// First mass of each spring.
    pub a: Vec<u32>,
    /// Second mass of each spring.
    pub b: Vec<u32>,
    /// Rest length of each spring (measured from the rest positions, so a cloth at rest feels no force).
    pub length: Vec<f32>,
    /// Spring constant of each spring.
    pub k: Vec<f32>,
    /// Damping of each spring.
    pub c: Vec<f32>,
    /// The same springs as offset families of a grid, when the cloth is one: the stepper then
    /// runs the vectorized stencil kernel instead of walking the spring list, and pins exactly the
    /// stencil's bottom row (as [`Topology::grid`] sets `pinned`).
    pub stencil: Option<GridStencil>,
}

impl Topology {
    /// Number of masses.
    pub fn masses(&self) -> usize {
        self.pinned.len()
    }

    /// Number of springs.
    pub fn springs(&self) -> usize {
        self.a.len()
    }

    /// A `grid_width × grid_height` cloth in the x–y plane, bottom row pinned at y = 0, centred
    /// on x = 0: structural springs (§Internal Forces) plus, as asked, shear and bend springs
    /// (Provot 1995).
    pub fn grid(p: &ClothParams) -> Topology {
        let (w, h) = (p.grid_width, p.grid_height);
        let n = w * h;
        let mut rest = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
        for r in 0..h {
            for col in 0..w {
                let i = r * w + col;
                rest[0][i] = (col as f32 / (w - 1).max(1) as f32 - 0.5) * p.flame_width;
                rest[1][i] = r as f32 / (h - 1).max(1) as f32 * p.flame_height;
            }
        }
        let pinned = (0..n).map(|i| i < w).collect();
        let mut t = Topology {
            pinned,
            rest,
            a: Vec::new(),
            b: Vec::new(),
            length: Vec::new(),
            k: Vec::new(),
            c: Vec::new(),
            stencil: None,
        };
        let idx = |r: usize, col: usize| r * w + col;
        for r in 0..h {
            for col in 0..w {
                if col + 1 < w {
                    t.add(idx(r, col), idx(r, col + 1), p.stiffness, p.damping);
                }
                if r + 1 < h {
                    t.add(idx(r, col), idx(r + 1, col), p.stiffness, p.damping);
                }
                if p.shear && col + 1 < w && r + 1 < h {
                    t.add(idx(r, col), idx(r + 1, col + 1), p.shear_stiffness, p.damping);
                    t.add(idx(r, col + 1), idx(r + 1, col), p.shear_stiffness, p.damping);
                }
                if p.bend && col + 2 < w {
                    t.add(idx(r, col), idx(r, col + 2), p.bend_stiffness, p.damping);
                }
                if p.bend && r + 2 < h {
                    t.add(idx(r, col), idx(r + 2, col), p.bend_stiffness, p.damping);
                }
            }
        }
        // The same springs, family by family (rows up, columns right, k).
        let mut families = vec![(0, 1, p.stiffness), (1, 0, p.stiffness)];
        if p.shear {
            families.extend([(1, 1, p.shear_stiffness), (1, -1, p.shear_stiffness)]);
        }
        if p.bend {
            families.extend([(0, 2, p.bend_stiffness), (2, 0, p.bend_stiffness)]);
        }
        let mut stencil = GridStencil::new(w, h);
        for (rows, cols, k) in families {
            stencil.add_family(rows, cols, k, p.damping, &t.rest);
        }
        t.stencil = Some(stencil);
        t
    }

    /// One spring of rest length `length` along x between a pinned mass at the origin and a free one.
    pub fn single_spring(length: f32, k: f32, c: f32) -> Topology {
        let rest = [vec![0.0, length], vec![0.0, 0.0], vec![0.0, 0.0]];
        let mut t = Topology {
            pinned: vec![true, false],
            rest,
            a: Vec::new(),
            b: Vec::new(),
            length: Vec::new(),
            k: Vec::new(),
            c: Vec::new(),
            stencil: None,
        };
        t.add(0, 1, k, c);
        t
    }

    fn add(&mut self, a: usize, b: usize, k: f32, c: f32) {
        let d =
            Vec3::new(self.rest[0][b] - self.rest[0][a], self.rest[1][b] - self.rest[1][a], self.rest[2][b] - self.rest[2][a]);
        self.a.push(a as u32);
        self.b.push(b as u32);
        self.length.push(d.length());
        self.k.push(k);
        self.c.push(c);
    }

    /// The longest stable semi-implicit Euler step for masses `mass` with air drag `drag`.
    ///
    /// For `x'' = −ω²x − γx'` semi-implicit Euler is stable iff `ω²h² + 2γh < 4`, i.e.
    /// `h < (√(γ² + 4ω²) − γ) / ω²` (which is `2·√(m/k)` without damping). The stiffest mode of
    /// the cloth is bounded (Gershgorin) by `ω² ≤ 2·max_i Σ k / m` over the springs at a mass,
    /// and likewise `γ ≤ (2·max_i Σ c + drag) / m`.
    pub fn stable_step(&self, mass: f32, drag: f32) -> f32 {
        let n = self.masses();
        let (mut sk, mut sc) = (vec![0.0f64; n], vec![0.0f64; n]);
        for s in 0..self.springs() {
            for m in [self.a[s] as usize, self.b[s] as usize] {
                sk[m] += self.k[s] as f64;
                sc[m] += self.c[s] as f64;
            }
        }
        let kmax = sk.iter().cloned().fold(0.0, f64::max);
        let cmax = sc.iter().cloned().fold(0.0, f64::max);
        let m = mass as f64;
        let w2 = 2.0 * kmax / m;
        let g = (2.0 * cmax + drag as f64) / m;
        if w2 <= 0.0 {
            return if g > 0.0 { (2.0 / g) as f32 } else { f32::INFINITY };
        }
        (((g * g + 4.0 * w2).sqrt() - g) / w2) as f32
    }
}

/// One flame's masses in structure-of-arrays form.
#[derive(Clone, Debug, PartialEq)]
pub struct FlameState {
    /// Positions, one array per axis (flame-local).
    pub pos: [Vec<f32>; 3],
    /// Velocities, one array per axis.
    pub vel: [Vec<f32>; 3],
    /// Offset of this flame's wind schedule in seconds (its random phase).
    pub phase: f32,
    /// Multiplier of the wind force for this flame.
    pub wind_scale: f32,
    /// This flame's seed (textures).
    pub seed: u32,
}

impl FlameState {
    /// A flame at rest.
    pub fn at_rest(topo: &Topology, phase: f32, wind_scale: f32, seed: u32) -> Self {
        let n = topo.masses();
        FlameState { pos: topo.rest.clone(), vel: [vec![0.0; n], vec![0.0; n], vec![0.0; n]], phase, wind_scale, seed }
    }

    /// Kinetic energy plus spring energy minus the work potential of the constant force `up`
    /// (buoyancy) — the energy that is conserved without damping and impulses.
    pub fn energy(&self, topo: &Topology, mass: f32, up: Vec3) -> f64 {
        let mut e = 0.0f64;
        for i in 0..topo.masses() {
            let v = Vec3::new(self.vel[0][i], self.vel[1][i], self.vel[2][i]);
            let p = Vec3::new(self.pos[0][i], self.pos[1][i], self.pos[2][i]);
            e += 0.5 * mass as f64 * v.length_squared() as f64 - up.dot(p) as f64;
        }
        for s in 0..topo.springs() {
            let (a, b) = (topo.a[s] as usize, topo.b[s] as usize);
            let d = Vec3::new(self.pos[0][b] - self.pos[0][a], self.pos[1][b] - self.pos[1][a], self.pos[2][b] - self.pos[2][a]);
            let x = (d.length() - topo.length[s]) as f64;
            e += 0.5 * topo.k[s] as f64 * x * x;
        }
        e
    }

    /// Advances `steps` semi-implicit Euler sub-steps of length `h` from time `t0` (seconds):
    /// forces from Hooke springs with damping (§Internal Forces), `external(t)` on every mass and
    /// drag; then `v += f/m·h`, `x += v·h` (§Integration eq. 1–3) for every unpinned mass.
    /// A grid topology runs the vectorized stencil kernel ([`stencil::advance`]); any other
    /// walks the spring list.
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &mut self,
        topo: &Topology,
        mass: f32,
        drag: f32,
        h: f32,
        steps: usize,
        t0: f64,
        external: impl Fn(f64) -> Vec3,
    ) {
        self.advance_checked(topo, mass, drag, h, steps, t0, external);
    }

    /// [`FlameState::advance`], returning whether the state is still finite afterwards.
    #[allow(clippy::too_many_arguments)]
    pub fn advance_checked(
        &mut self,
        topo: &Topology,
        mass: f32,
        drag: f32,
        h: f32,
        steps: usize,
        t0: f64,
        external: impl Fn(f64) -> Vec3,
    ) -> bool {
        let n = topo.masses();
        if let Some(st) = topo.stencil.as_ref().filter(|st| st.masses() == n) {
            let consts = stencil::StepConsts { mass, drag, h, steps, t0 };
            return stencil::with_scratch(|s| stencil::advance(st, &mut self.pos, &mut self.vel, s, consts, &external));
        }
        self.advance_springs(topo, mass, drag, h, steps, t0, external);
        self.is_finite()
    }

    /// [`FlameState::advance`] by walking the spring list (any topology); the reference the
    /// stencil kernel is tested against.
    #[allow(clippy::too_many_arguments)]
    pub fn advance_springs(
        &mut self,
        topo: &Topology,
        mass: f32,
        drag: f32,
        h: f32,
        steps: usize,
        t0: f64,
        external: impl Fn(f64) -> Vec3,
    ) {
        let n = topo.masses();
        let mut f = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
        let inv_m = 1.0 / mass;
        for step in 0..steps {
            let ext = external(t0 + step as f64 * h as f64);
            let [px, py, pz] = &mut self.pos;
            let [vx, vy, vz] = &mut self.vel;
            let [fx, fy, fz] = &mut f;
            for i in 0..n {
                fx[i] = ext.x - drag * vx[i];
                fy[i] = ext.y - drag * vy[i];
                fz[i] = ext.z - drag * vz[i];
            }
            let springs = topo.a.iter().zip(&topo.b).zip(&topo.length).zip(&topo.k).zip(&topo.c);
            for ((((&a, &b), &rest), &k), &c) in springs {
                let (a, b) = (a as usize, b as usize);
                let (dx, dy, dz) = (px[b] - px[a], py[b] - py[a], pz[b] - pz[a]);
                let len = (dx * dx + dy * dy + dz * dz).sqrt();
                if len <= 1e-12 {
                    continue;
                }
                let inv = 1.0 / len;
                let (ux, uy, uz) = (dx * inv, dy * inv, dz * inv);
                let rel = (vx[b] - vx[a]) * ux + (vy[b] - vy[a]) * uy + (vz[b] - vz[a]) * uz;
                // Hooke's law f = −k·Δl (Equation 4) plus a damper along the spring.
                let mag = k * (len - rest) + c * rel;
                let (gx, gy, gz) = (mag * ux, mag * uy, mag * uz);
                fx[a] += gx;
                fy[a] += gy;
                fz[a] += gz;
                fx[b] -= gx;
                fy[b] -= gy;
                fz[b] -= gz;
            }
            for i in 0..n {
                if topo.pinned[i] {
                    continue;
                }
                vx[i] += fx[i] * inv_m * h;
                vy[i] += fy[i] * inv_m * h;
                vz[i] += fz[i] * inv_m * h;
                px[i] += vx[i] * h;
                py[i] += vy[i] * h;
                pz[i] += vz[i] * h;
            }
        }
    }

    fn is_finite(&self) -> bool {
        self.pos.iter().chain(&self.vel).all(|a| a.iter().all(|x| x.is_finite()))
    }
}

/// Whether the wind impulse is on at time `t` (seconds) for a flame with phase `phase`:
/// `wind_on` seconds on, then `wind_off` seconds off, repeating (§External Forces).
pub fn wind_active(t: f64, phase: f32, wind_on: f32, wind_off: f32) -> bool {
    let period = (wind_on + wind_off) as f64;
    if wind_on <= 0.0 || period <= 0.0 {
        return false;
    }
    (t + phase as f64).rem_euclid(period) < wind_on as f64
}

/// Checks what no port range can; errors name the port.
pub fn validate(p: &ClothParams) -> Result<(), NodeError> {
    if p.grid_width < 2 {
        return Err(NodeError::port("grid_width", format!("a cloth needs at least 2×2 masses, got width {}", p.grid_width)));
    }
    if p.grid_height < 2 {
        return Err(NodeError::port("grid_height", format!("a cloth needs at least 2×2 masses, got height {}", p.grid_height)));
    }
    let scalars = [
        ("flame_width", p.flame_width),
        ("flame_height", p.flame_height),
        ("mass", p.mass),
        ("stiffness", p.stiffness),
        ("damping", p.damping),
        ("shear_stiffness", p.shear_stiffness),
        ("bend_stiffness", p.bend_stiffness),
        ("drag", p.drag),
        ("buoyancy", p.buoyancy),
        ("wind_on", p.wind_on),
        ("wind_off", p.wind_off),
        ("wind_jitter", p.wind_jitter),
        ("dt", p.dt),
        ("fps", p.fps),
    ];
    for (name, v) in scalars {
        if !v.is_finite() {
            return Err(NodeError::port(name, format!("must be finite, got {v}")));
        }
    }
    if !p.wind.is_finite() {
        return Err(NodeError::port("wind", format!("must be finite, got {}", p.wind)));
    }
    if p.mass <= 0.0 {
        return Err(NodeError::port("mass", format!("must be positive, got {}", p.mass)));
    }
    for (name, v) in [("flame_width", p.flame_width), ("flame_height", p.flame_height), ("dt", p.dt), ("fps", p.fps)] {
        if v <= 0.0 {
            return Err(NodeError::port(name, format!("must be positive, got {v}")));
        }
    }
    for (name, v) in [
        ("stiffness", p.stiffness),
        ("damping", p.damping),
        ("shear_stiffness", p.shear_stiffness),
        ("bend_stiffness", p.bend_stiffness),
        ("drag", p.drag),
        ("wind_on", p.wind_on),
        ("wind_off", p.wind_off),
        ("wind_jitter", p.wind_jitter),
    ] {
        if v < 0.0 {
            return Err(NodeError::port(name, format!("must not be negative, got {v}")));
        }
    }
    Ok(())
}

/// Checks `p.dt` against the stability limit of [`Topology::stable_step`].
pub fn check_step(topo: &Topology, p: &ClothParams) -> Result<(), NodeError> {
    let limit = topo.stable_step(p.mass, p.drag);
    if p.dt.is_nan() || p.dt >= limit {
        return Err(NodeError::port(
            "dt",
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

/// A whole simulation: shared topology, every flame's state and the frame it has reached.
#[derive(Clone, Debug)]
pub struct Simulation {
    topo: Arc<Topology>,
    params: ClothParams,
    roots: Vec<Vec3>,
    flames: Vec<FlameState>,
    frame: usize,
}

impl Simulation {
    /// Flames at rest at `roots`, each with its own phase, wind strength and seed drawn from
    /// `params.seed`. Validates the parameters and the step.
    pub fn new(params: &ClothParams, roots: &[Vec3]) -> Result<Self, NodeError> {
        validate(params)?;
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
        self.advance_flames(h, steps);
    }

    /// Advances every flame by `steps` sub-steps of length `h`, each flame all its sub-steps at
    /// once while its masses are in cache; flames in parallel chunks when there is enough work.
    /// Returns the first flame whose state is no longer finite.
    fn advance_flames(&mut self, h: f32, steps: usize) -> Option<usize> {
        let t0 = self.frame as f64 / self.params.fps as f64;
        let (topo, p) = (&*self.topo, &self.params);
        let work = |(i, f): (usize, &mut FlameState)| {
            let ext = external(p, f.phase, f.wind_scale);
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
    pub fn step_frame(&mut self) -> Result<(), NodeError> {
        let (n, h) = self.substeps();
        let bad = self.advance_flames(h, n);
        self.frame += 1;
        if let Some(i) = bad {
            return Err(NodeError::port(
                "dt",
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

    fn bytes(&self) -> usize {
        self.flames.len() * self.topo.masses() * 24 + 64
    }
}

/// Mass-steps (flames × masses × sub-steps) below which a call steps its flames on one thread:
/// less work than this does not pay for waking the pool.
const PARALLEL_WORK: usize = 16_384;

/// The external force on every mass of a flame at time `t`: buoyancy, plus the flame's wind
/// while an impulse is on (§External Forces).
fn external(p: &ClothParams, phase: f32, wind_scale: f32) -> impl Fn(f64) -> Vec3 + use<> {
    let (up, wind, on, off) = (Vec3::Y * p.buoyancy, p.wind * wind_scale, p.wind_on, p.wind_off);
    move |t| if wind_active(t, phase, on, off) { up + wind } else { up }
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

/// Checkpoints of the full state are kept every this many frames (within [`CHECKPOINT_BUDGET`]).
pub const CHECKPOINT_EVERY: usize = 24;
/// Bytes of full-state checkpoints one clip keeps.
pub const CHECKPOINT_BUDGET: usize = 256 << 20;
/// Bytes of recently passed frame snapshots one clip keeps (for parallel pulls).
pub const SNAPSHOT_BUDGET: usize = 128 << 20;

struct Cache {
    /// The last simulated state (taken out while a caller steps it, so no lock is held while
    /// rayon runs).
    current: Option<Simulation>,
    checkpoints: BTreeMap<usize, Simulation>,
    checkpoint_bytes: usize,
    snapshots: BTreeMap<usize, Arc<ClothState>>,
    snapshot_order: VecDeque<usize>,
    snapshot_bytes: usize,
}

impl Cache {
    fn put_snapshot(&mut self, frame: usize, s: &Arc<ClothState>) {
        if self.snapshots.contains_key(&frame) {
            return;
        }
        self.snapshot_bytes += Value::ClothState(s.clone()).byte_size();
        self.snapshots.insert(frame, s.clone());
        self.snapshot_order.push_back(frame);
        while self.snapshot_bytes > SNAPSHOT_BUDGET && self.snapshot_order.len() > 1 {
            let Some(old) = self.snapshot_order.pop_front() else { break };
            if let Some(v) = self.snapshots.remove(&old) {
                self.snapshot_bytes -= Value::ClothState(v).byte_size();
            }
        }
    }
}

/// A clip of cloth states backed by a stepping cache: frame `n` after frame `n − 1` costs one
/// frame of steps; an earlier frame restarts from the nearest checkpoint (or the start).
pub struct ClothSource {
    initial: Simulation,
    frames: usize,
    cache: Mutex<Cache>,
    stepped: AtomicUsize,
}

impl ClothSource {
    /// A source of `frames` frames starting from `initial` (frame 0 is the cloth at rest).
    pub fn new(initial: Simulation, frames: usize) -> Self {
        let cache = Cache {
            current: None,
            checkpoints: BTreeMap::new(),
            checkpoint_bytes: 0,
            snapshots: BTreeMap::new(),
            snapshot_order: VecDeque::new(),
            snapshot_bytes: 0,
        };
        ClothSource { initial, frames, cache: Mutex::new(cache), stepped: AtomicUsize::new(0) }
    }

    /// Frames of simulation stepped so far (each is all the sub-steps of one frame).
    pub fn frames_stepped(&self) -> usize {
        self.stepped.load(Ordering::Relaxed)
    }

    fn lock(&self) -> Result<std::sync::MutexGuard<'_, Cache>, NodeError> {
        self.cache.lock().map_err(|_| NodeError::msg("the cloth cache was poisoned by an earlier panic"))
    }

    /// The state at `index`.
    pub fn state(&self, index: usize, ctx: &CookCtx) -> Result<Arc<ClothState>, NodeError> {
        let mut sim = {
            let mut c = self.lock()?;
            if let Some(s) = c.snapshots.get(&index) {
                return Ok(s.clone());
            }
            match c.current.take() {
                Some(cur) if cur.frame <= index => cur,
                other => {
                    c.current = other;
                    c.checkpoints.range(..=index).next_back().map(|(_, s)| s.clone()).unwrap_or_else(|| self.initial.clone())
                }
            }
        };
        let mut last = None;
        while sim.frame < index {
            ctx.check_cancel()?;
            sim.step_frame()?;
            self.stepped.fetch_add(1, Ordering::Relaxed);
            let snap = Arc::new(sim.snapshot());
            let mut c = self.lock()?;
            c.put_snapshot(sim.frame, &snap);
            last = Some(snap);
            if sim.frame % CHECKPOINT_EVERY == 0
                && !c.checkpoints.contains_key(&sim.frame)
                && c.checkpoint_bytes + sim.bytes() <= CHECKPOINT_BUDGET
            {
                c.checkpoint_bytes += sim.bytes();
                c.checkpoints.insert(sim.frame, sim.clone());
            }
        }
        let snap = match last {
            Some(s) => s,
            None => Arc::new(sim.snapshot()),
        };
        let mut c = self.lock()?;
        c.put_snapshot(index, &snap);
        if c.current.as_ref().is_none_or(|cur| cur.frame <= sim.frame) {
            c.current = Some(sim);
        }
        Ok(snap)
    }
}

impl FrameSource for ClothSource {
    fn len(&self) -> usize {
        self.frames
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::ClothState(self.state(index, ctx)?))
    }
}

fn vec3_port(name: &str, default: [f64; 3], doc: &str) -> PortDesc {
    PortDesc { default: Some(Value::Vec3(default)), ..PortDesc::new(name, PortType::Vec3, doc) }
}

fn mass_spring_flame_desc() -> NodeDesc {
    let d = ClothParams::default();
    NodeDesc::new(
        "cloth.mass_spring_flame",
        "Cloth",
        TimeDep::Simulation,
        "Mass-spring flames, the silk torch of the mass-spring flame project 2019 (after Balci & Foroosh 2006): \
         each flame is a grid_width × grid_height cloth of masses joined by horizontal and vertical Hooke springs \
         f = −k·Δl with a damper (§Internal Forces, Equation 4), plus optional shear and bend springs for \
         stability (Provot 1995). The bottom row is pinned; buoyancy pushes every mass up so the cloth \"falls \
         upwards\", and wind is a force vector applied in impulses, wind_on seconds on and wind_off seconds off \
         (§External Forces: 1 s on, 5 s off). Integration is semi-implicit Euler, v += f/m·dt, x += v·dt \
         (§Integration, Equations 1–3), in equal sub-steps no longer than dt, so any fps is stable; dt is \
         checked against the stability limit ≈ 2·√(m/k_eff). Flames stand on a grid of `count` (or at the \
         points of a connected particles.roots), each with its own random wind phase, strength and seed. \
         Deterministic for a seed; the clip steps a cache, so frame n after n − 1 costs one frame. Render with \
         cloth.cloth_render or cloth.cloth_render_textured.",
    )
    .input(PortDesc {
        default: Some(Value::Particles(Arc::new(Particles::default()))),
        ..PortDesc::new(
            "roots",
            PortType::Particles,
            "Optional flame roots (particles.roots); when none are connected, `count` flames stand on a grid.",
        )
    })
    .input(PortDesc::int("count", 9, (1, 1_000_000), "Flames on the grid when no roots are connected (the project: 9 … 144)."))
    .input(PortDesc::float("spacing", 1.5, (0.0, 1e6), "Distance between grid flames."))
    .input(PortDesc::int("frames", 120, (1, 100_000), "Number of frames."))
    .input(PortDesc::float("fps", 24.0, (1.0, 1000.0), "Frames per second."))
    .input(PortDesc::int("grid_width", 16, (2, 1024), "Masses per row (the project: 16)."))
    .input(PortDesc::int("grid_height", 32, (2, 1024), "Rows of masses, the bottom one pinned (the project: 32)."))
    .input(PortDesc::float("flame_width", d.flame_width as f64, (1e-6, 1e6), "Rest width of a cloth."))
    .input(PortDesc::float("flame_height", d.flame_height as f64, (1e-6, 1e6), "Rest height of a cloth."))
    .input(PortDesc::float("mass", d.mass as f64, (1e-9, 1e9), "Mass of every mass point (f = m·a, §Integration)."))
    .input(PortDesc::float("stiffness", d.stiffness as f64, (0.0, 1e9), "Spring constant k of the structural springs (Hooke)."))
    .input(PortDesc::float("damping", d.damping as f64, (0.0, 1e9), "Damping of every spring along its axis."))
    .input(PortDesc::bool("shear", true, "Add diagonal shear springs (Provot 1995)."))
    .input(PortDesc::float("shear_stiffness", d.shear_stiffness as f64, (0.0, 1e9), "Spring constant of the shear springs."))
    .input(PortDesc::bool("bend", true, "Add bend springs spanning two cells (Provot 1995)."))
    .input(PortDesc::float("bend_stiffness", d.bend_stiffness as f64, (0.0, 1e9), "Spring constant of the bend springs."))
    .input(PortDesc::float("drag", d.drag as f64, (0.0, 1e9), "Air drag: force −drag·v on every mass."))
    .input(PortDesc::float("buoyancy", d.buoyancy as f64, (-1e9, 1e9), "Upward force on every mass (§External Forces)."))
    .input(vec3_port(
        "wind",
        [0.03, 0.0, 0.01],
        "Wind force on every mass during an impulse (flame-local: x across, y up, z toward the viewer).",
    ))
    .input(PortDesc::float("wind_on", 1.0, (0.0, 1e6), "Seconds each wind impulse lasts (the project: 1 s)."))
    .input(PortDesc::float("wind_off", 5.0, (0.0, 1e6), "Seconds between wind impulses (the project: 5 s)."))
    .input(PortDesc::float("wind_jitter", d.wind_jitter as f64, (0.0, 1.0), "Random per-flame variation of the wind strength."))
    .input(PortDesc::float("dt", d.dt as f64, (1e-7, 10.0), "Longest integration sub-step in seconds (checked for stability)."))
    .input(PortDesc::int("seed", 0, (0, u32::MAX as i64), "Seed of the per-flame phases, wind strengths and textures."))
    .output("cloth", PortType::clip_of(PortType::ClothState), "Per frame, every flame's cloth.")
}

fn f32_port(i: &Inputs<'_>, name: &str) -> Result<f32, NodeError> {
    Ok(i.float(name)? as f32)
}

/// Reads [`ClothParams`] from the node's inputs and validates them; errors name the port.
pub fn params_from_inputs(i: &Inputs<'_>) -> Result<ClothParams, NodeError> {
    let grid = |name: &str| -> Result<usize, NodeError> {
        let v = i.int(name)?;
        if v < 2 {
            return Err(NodeError::port(name, format!("a cloth needs at least 2×2 masses, got {v}")));
        }
        usize::try_from(v).map_err(|_| NodeError::port(name, "too large"))
    };
    let wind = i.vec3("wind")?;
    let seed = i.int("seed")?;
    let p = ClothParams {
        grid_width: grid("grid_width")?,
        grid_height: grid("grid_height")?,
        flame_width: f32_port(i, "flame_width")?,
        flame_height: f32_port(i, "flame_height")?,
        mass: f32_port(i, "mass")?,
        stiffness: f32_port(i, "stiffness")?,
        damping: f32_port(i, "damping")?,
        shear: i.bool("shear")?,
        shear_stiffness: f32_port(i, "shear_stiffness")?,
        bend: i.bool("bend")?,
        bend_stiffness: f32_port(i, "bend_stiffness")?,
        drag: f32_port(i, "drag")?,
        buoyancy: f32_port(i, "buoyancy")?,
        wind: Vec3::new(wind[0] as f32, wind[1] as f32, wind[2] as f32),
        wind_on: f32_port(i, "wind_on")?,
        wind_off: f32_port(i, "wind_off")?,
        wind_jitter: f32_port(i, "wind_jitter")?,
        dt: f32_port(i, "dt")?,
        fps: f32_port(i, "fps")?,
        seed: u32::try_from(seed).map_err(|_| NodeError::port("seed", format!("must be 0..=4294967295, got {seed}")))?,
    };
    validate(&p)?;
    Ok(p)
}

fn cook_mass_spring_flame(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let params = params_from_inputs(i)?;
    let roots_value = i.get("roots")?;
    let given = i.particles("roots")?;
    let roots: Vec<Vec3> = if given.particles.is_empty() {
        let spacing = f32_port(i, "spacing")?;
        if !spacing.is_finite() {
            return Err(NodeError::port("spacing", "must be finite"));
        }
        grid_roots(i.usize("count")?, spacing)
    } else {
        given.particles.iter().map(|q| Vec3::from_array(q.position)).collect()
    };
    if let Some(k) = roots.iter().position(|r| !r.is_finite()) {
        return Err(NodeError::port("roots", format!("root {k} has a non-finite position")));
    }
    let frames = i.usize("frames")?;
    if frames == 0 {
        return Err(NodeError::port("frames", "must be at least 1"));
    }
    let sim = Simulation::new(&params, &roots)?;
    let mut h = Fingerprinter::new();
    "cloth.mass_spring_flame".hash(&mut h);
    roots_value.hash_into(&mut h);
    roots.iter().for_each(|r| r.to_array().map(f32::to_bits).hash(&mut h));
    format!("{params:?}").hash(&mut h);
    frames.hash(&mut h);
    let clip = Clip::new(PortType::ClothState, params.fps as f64, h.finish(), Arc::new(ClothSource::new(sim, frames)));
    Ok(vec![Value::Clip(clip)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn calm() -> ClothParams {
        ClothParams { buoyancy: 0.0, wind: Vec3::ZERO, ..ClothParams::default() }
    }

    #[test]
    fn one_spring_oscillates_at_its_analytic_frequency() {
        let (k, m, amp) = (40.0f32, 0.1f32, 0.05f32);
        let topo = Topology::single_spring(1.0, k, 0.0);
        let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
        f.pos[0][1] += amp;
        let h = 1e-4f32;
        let mut crossings = Vec::new();
        let mut prev = f.pos[0][1] - 1.0;
        for s in 1..200_000 {
            f.advance(&topo, m, 0.0, h, 1, 0.0, |_| Vec3::ZERO);
            let x = f.pos[0][1] - 1.0;
            if prev > 0.0 && x <= 0.0 {
                // Linear interpolation of the downward zero crossing.
                crossings.push((s as f64 - 1.0 + prev as f64 / (prev - x) as f64) * h as f64);
            }
            prev = x;
        }
        assert!(crossings.len() > 10, "{crossings:?}");
        let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let analytic = std::f64::consts::TAU * (m as f64 / k as f64).sqrt();
        assert!((measured / analytic - 1.0).abs() < 0.01, "period {measured} vs analytic {analytic}");
    }

    #[test]
    fn a_two_by_two_stencil_grid_bobs_at_its_analytic_frequency() {
        // Both top masses hang on one vertical spring each; moved up together, the horizontal
        // spring between them stays at rest, so each bobs at ω = √(k/m).
        let p = ClothParams {
            grid_width: 2,
            grid_height: 2,
            shear: false,
            bend: false,
            stiffness: 40.0,
            mass: 0.1,
            damping: 0.0,
            ..calm()
        };
        let topo = Topology::grid(&p);
        assert!(topo.stencil.is_some(), "the grid runs the stencil kernel");
        let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
        let rest_y = f.pos[1][2];
        f.pos[1][2] += 0.05;
        f.pos[1][3] += 0.05;
        let h = 1e-4f32;
        let (mut crossings, mut prev) = (Vec::new(), 0.05f32);
        for s in 1..100_000 {
            f.advance(&topo, p.mass, 0.0, h, 1, 0.0, |_| Vec3::ZERO);
            let y = f.pos[1][2] - rest_y;
            if prev > 0.0 && y <= 0.0 {
                crossings.push((s as f64 - 1.0 + prev as f64 / (prev - y) as f64) * h as f64);
            }
            prev = y;
        }
        assert!(crossings.len() > 10, "{crossings:?}");
        let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let analytic = std::f64::consts::TAU * (p.mass as f64 / p.stiffness as f64).sqrt();
        assert!((measured / analytic - 1.0).abs() < 0.01, "period {measured} vs analytic {analytic}");
        assert_eq!(f.pos[1][2].to_bits(), f.pos[1][3].to_bits(), "the two top masses move together");
    }

    #[test]
    fn the_stencil_kernel_matches_the_spring_list() {
        for (shear, bend) in [(false, false), (true, false), (true, true)] {
            let p = ClothParams { grid_width: 7, grid_height: 9, shear, bend, wind_jitter: 0.0, ..ClothParams::default() };
            let topo = Topology::grid(&p);
            let st = topo.stencil.as_ref().unwrap();
            let counted: usize = st.families.iter().map(|f| f.rest.len() - f.cut.len()).sum();
            assert_eq!(counted, topo.springs(), "shear {shear} bend {bend}: the families hold every spring");
            let (mut a, mut b) = (FlameState::at_rest(&topo, 0.0, 1.0, 0), FlameState::at_rest(&topo, 0.0, 1.0, 0));
            let ext = |t: f64| Vec3::new(0.05 * (3.0 * t).sin() as f32, p.buoyancy, 0.02);
            let h = 1.0 / 600.0;
            for k in 0..60 {
                a.advance(&topo, p.mass, p.drag, h, 10, k as f64 / 60.0, ext);
                b.advance_springs(&topo, p.mass, p.drag, h, 10, k as f64 / 60.0, ext);
            }
            let mut worst = 0.0f32;
            for axis in 0..3 {
                for i in 0..topo.masses() {
                    worst = worst.max((a.pos[axis][i] - b.pos[axis][i]).abs());
                }
            }
            let moved = (a.pos[0][topo.masses() - 1] - topo.rest[0][topo.masses() - 1]).abs();
            assert!(moved > 0.01, "the cloth moved: {moved}");
            assert!(worst < 1e-4, "shear {shear} bend {bend}: stencil and spring list differ by {worst}");
        }
    }

    #[test]
    fn a_diverging_step_is_reported_not_returned_as_nan() {
        // Past the stability limit (bypassing the check) the stepper reports the flame.
        let p = ClothParams::default();
        let mut sim = Simulation::new(&p, &grid_roots(2, 1.5)).unwrap();
        sim.params.dt = 0.05;
        let err = (0..50).find_map(|_| sim.step_frame().err());
        assert!(matches!(err, Some(NodeError::Port { ref port, .. }) if port == "dt"), "{err:?}");
    }

    #[test]
    fn without_wind_and_buoyancy_the_grid_stays_at_rest() {
        let mut sim = Simulation::new(&calm(), &grid_roots(4, 1.5)).unwrap();
        let start = sim.snapshot();
        for _ in 0..48 {
            sim.step_frame().unwrap();
        }
        assert_eq!(sim.snapshot().positions, start.positions);
    }

    #[test]
    fn the_pinned_row_never_moves_and_the_cloth_rises_and_sways() {
        let p = ClothParams { wind_jitter: 0.0, ..ClothParams::default() };
        let mut sim = Simulation::new(&p, &grid_roots(3, 1.5)).unwrap();
        let rest = sim.snapshot();
        let w = p.grid_width;
        let n = p.grid_width * p.grid_height;
        let mut moved = 0.0f32;
        for _ in 0..150 {
            sim.step_frame().unwrap();
            let s = sim.snapshot();
            for f in 0..3 {
                assert_eq!(s.positions[f * n..f * n + w], rest.positions[f * n..f * n + w], "flame {f}");
                let top = s.positions[f * n + n - 1];
                moved = moved.max((top[0] - rest.positions[f * n + n - 1][0]).abs());
            }
        }
        assert!(moved > 0.05, "the wind impulses move the tips: {moved}");
    }

    #[test]
    fn with_damping_energy_never_grows_after_the_impulse() {
        let p = ClothParams { wind_jitter: 0.0, damping: 0.05, drag: 0.01, ..ClothParams::default() };
        let topo = Topology::grid(&p);
        let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
        let up = Vec3::Y * p.buoyancy;
        let h = 1.0 / 600.0;
        // The impulse is on for the first second (phase 0), then off for five.
        let ext = |t: f64| if wind_active(t, 0.0, p.wind_on, p.wind_off) { up + p.wind } else { up };
        f.advance(&topo, p.mass, p.drag, h, 600, 0.0, ext);
        let mut e = f.energy(&topo, p.mass, up);
        for k in 0..240 {
            f.advance(&topo, p.mass, p.drag, h, 10, 1.0 + k as f64 / 60.0, ext);
            let next = f.energy(&topo, p.mass, up);
            assert!(next <= e + 1e-6 * e.abs().max(1e-3), "step {k}: energy grew from {e} to {next}");
            e = next;
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_frames_and_random_access_matches_stepping() {
        let p = ClothParams { seed: 7, ..ClothParams::default() };
        let roots = grid_roots(5, 1.5);
        let ctx = CookCtx::default();
        let a = ClothSource::new(Simulation::new(&p, &roots).unwrap(), 60);
        let b = ClothSource::new(Simulation::new(&p, &roots).unwrap(), 60);
        let forward: Vec<_> = (0..60).map(|k| a.state(k, &ctx).unwrap()).collect();
        for k in [59, 3, 30, 0, 31] {
            assert_eq!(*b.state(k, &ctx).unwrap(), *forward[k], "frame {k}");
        }
        assert_eq!(a.frames_stepped(), 59, "sequential access steps one frame per frame");
        let other = ClothSource::new(Simulation::new(&ClothParams { seed: 8, ..p }, &roots).unwrap(), 60);
        assert_ne!(other.state(40, &ctx).unwrap().positions, forward[40].positions);
    }

    #[test]
    fn bad_inputs_are_errors_naming_the_port() {
        let port = |p: ClothParams| match Simulation::new(&p, &[Vec3::ZERO]) {
            Err(NodeError::Port { port, .. }) => port,
            other => panic!("expected a port error, got {other:?}"),
        };
        assert_eq!(port(ClothParams { grid_width: 1, ..ClothParams::default() }), "grid_width");
        assert_eq!(port(ClothParams { grid_height: 1, ..ClothParams::default() }), "grid_height");
        assert_eq!(port(ClothParams { mass: -1.0, ..ClothParams::default() }), "mass");
        assert_eq!(port(ClothParams { dt: 0.05, ..ClothParams::default() }), "dt");
        assert_eq!(port(ClothParams { stiffness: f32::NAN, ..ClothParams::default() }), "stiffness");
        // Just under the limit is accepted and stays finite.
        let p = ClothParams::default();
        let limit = Topology::grid(&p).stable_step(p.mass, p.drag);
        let mut sim = Simulation::new(&ClothParams { dt: limit * 0.95, ..p.clone() }, &[Vec3::ZERO]).unwrap();
        for _ in 0..100 {
            sim.step_frame().unwrap();
        }
        assert!(sim.snapshot().positions.iter().all(|q| q.iter().all(|x| x.is_finite())));
    }

    #[test]
    fn the_node_refuses_a_small_grid_and_a_negative_mass() {
        let desc = mass_spring_flame_desc();
        let values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or(Value::Int(0))).collect();
        let port_of = |values: &[Value]| match cook_mass_spring_flame(&Inputs::new(&desc, values), &CookCtx::default()) {
            Err(NodeError::Port { port, .. }) => port,
            other => panic!("expected a port error, got {other:?}"),
        };
        let mut v = values.clone();
        v[desc.input_index("grid_width").unwrap()] = Value::Int(1);
        assert_eq!(port_of(&v), "grid_width");
        let mut v = values.clone();
        v[desc.input_index("mass").unwrap()] = Value::Float(-0.5);
        assert_eq!(port_of(&v), "mass");
        let mut v = values;
        v[desc.input_index("dt").unwrap()] = Value::Float(1.0);
        assert_eq!(port_of(&v), "dt");
    }
}
