//! The cloth model: the springs and masses shared by every flame ([`Topology`]), one flame's
//! state ([`FlameState`]) and its semi-implicit Euler stepper (§Integration, §Internal Forces).

use glam::Vec3;

use super::cloth_params::ClothParams;
use crate::stencil::{self, GridStencil};

/// A deterministic uniform number in 0..1 from `(seed, flame, salt)` (SplitMix64).
pub fn unit_random(seed: u32, flame: usize, salt: u64) -> f32 {
    (mix(seed, flame, salt) >> 40) as f32 / (1u64 << 24) as f32
}

pub(crate) fn mix(seed: u32, flame: usize, salt: u64) -> u64 {
    let mut z = (seed as u64) ^ ((flame as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) ^ salt.wrapping_mul(0xD1B5_4A32_D192_ED69);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
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
