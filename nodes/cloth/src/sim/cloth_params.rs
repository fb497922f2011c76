//! The parameters of a mass-spring flame simulation ([`ClothParams`], the ports of
//! `cloth.mass_spring_flame` after its roots and frames) and the checks no port range can make.

use glam::Vec3;
use pyrograph_core::declare::Anim;
use pyrograph_core::{NodeError, port};

use super::error::ClothError;

pyrograph_core::ports! {
    /// Every parameter of a mass-spring flame simulation: the ports of `cloth.mass_spring_flame`
    /// after its roots and frames.
    #[derive(PartialEq)]
    pub struct ClothParams {
        /// Frames per second.
        #[range(1.0, 1000.0)]
        fps: f32 = 24.0,
        /// Masses per row (the project: 16).
        #[range(2, 1024)]
        grid_width: usize = 16,
        /// Rows of masses, the bottom one pinned (the project: 32).
        #[range(2, 1024)]
        grid_height: usize = 32,
        /// Rest width of a cloth.
        #[range(1e-6, 1e6)]
        flame_width: f32 = 1.0,
        /// Rest height of a cloth.
        #[range(1e-6, 1e6)]
        flame_height: f32 = 2.0,
        /// Mass of every mass point (f = m·a, §Integration).
        #[range(1e-9, 1e9)]
        mass: f32 = 0.005,
        /// Spring constant k of the structural springs (Hooke).
        #[range(0.0, 1e9)]
        stiffness: f32 = 100.0,
        /// Damping of every spring along its axis.
        #[range(0.0, 1e9)]
        damping: f32 = 0.02,
        /// Add diagonal shear springs (Provot 1995).
        shear: bool = true,
        /// Spring constant of the shear springs.
        #[range(0.0, 1e9)]
        shear_stiffness: f32 = 30.0,
        /// Add bend springs spanning two cells (Provot 1995).
        bend: bool = true,
        /// Spring constant of the bend springs.
        #[range(0.0, 1e9)]
        bend_stiffness: f32 = 15.0,
        /// Air drag: force −drag·v on every mass.
        #[range(0.0, 1e9)]
        drag: f32 = 0.004,
        /// Upward force on every mass (§External Forces); sampled at every sub-step.
        #[range(-1e9, 1e9)]
        buoyancy: Anim<f32> = Anim::constant(0.05),
        /// Wind force on every mass during an impulse (flame-local: x across, y up, z toward the viewer); sampled at every sub-step.
        wind: Anim<[f32; 3]> = Anim::constant([0.03, 0.0, 0.01]),
        /// Seconds each wind impulse lasts (the project: 1 s).
        #[range(0.0, 1e6)]
        wind_on: f32 = 1.0,
        /// Seconds between wind impulses (the project: 5 s).
        #[range(0.0, 1e6)]
        wind_off: f32 = 5.0,
        /// Random per-flame variation of the wind strength.
        #[range(0.0, 1.0)]
        wind_jitter: f32 = 0.3,
        /// Longest integration sub-step in seconds (checked for stability).
        #[range(1e-7, 10.0)]
        dt: f32 = 1.0 / 600.0,
        /// Seed of the per-flame phases, wind strengths and textures.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

impl ClothParams {
    /// The port of the sub-step length, which the stability check and a diverged step blame.
    pub(crate) fn dt_port() -> &'static str {
        port!(ClothParams, dt)
    }

    /// Checks what no port range can; errors name the port.
    pub fn validate(&self) -> Result<(), ClothError> {
        let p = self;
        if p.grid_width < 2 {
            return Err(ClothError::new(
                port!(ClothParams, grid_width),
                format!("a cloth needs at least 2×2 masses, got width {}", p.grid_width),
            ));
        }
        if p.grid_height < 2 {
            return Err(ClothError::new(
                port!(ClothParams, grid_height),
                format!("a cloth needs at least 2×2 masses, got height {}", p.grid_height),
            ));
        }
        let scalars = [
            (port!(ClothParams, flame_width), p.flame_width),
            (port!(ClothParams, flame_height), p.flame_height),
            (port!(ClothParams, mass), p.mass),
            (port!(ClothParams, stiffness), p.stiffness),
            (port!(ClothParams, damping), p.damping),
            (port!(ClothParams, shear_stiffness), p.shear_stiffness),
            (port!(ClothParams, bend_stiffness), p.bend_stiffness),
            (port!(ClothParams, drag), p.drag),
            (port!(ClothParams, buoyancy), *p.buoyancy.value()),
            (port!(ClothParams, wind_on), p.wind_on),
            (port!(ClothParams, wind_off), p.wind_off),
            (port!(ClothParams, wind_jitter), p.wind_jitter),
            (port!(ClothParams, dt), p.dt),
            (port!(ClothParams, fps), p.fps),
        ];
        for (name, v) in scalars {
            if !v.is_finite() {
                return Err(ClothError::new(name, format!("must be finite, got {v}")));
            }
        }
        let wind = Vec3::from_array(*p.wind.value());
        if !wind.is_finite() {
            return Err(ClothError::new(port!(ClothParams, wind), format!("must be finite, got {wind}")));
        }
        if p.mass <= 0.0 {
            return Err(ClothError::new(port!(ClothParams, mass), format!("must be positive, got {}", p.mass)));
        }
        for (name, v) in [
            (port!(ClothParams, flame_width), p.flame_width),
            (port!(ClothParams, flame_height), p.flame_height),
            (port!(ClothParams, dt), p.dt),
            (port!(ClothParams, fps), p.fps),
        ] {
            if v <= 0.0 {
                return Err(ClothError::new(name, format!("must be positive, got {v}")));
            }
        }
        for (name, v) in [
            (port!(ClothParams, stiffness), p.stiffness),
            (port!(ClothParams, damping), p.damping),
            (port!(ClothParams, shear_stiffness), p.shear_stiffness),
            (port!(ClothParams, bend_stiffness), p.bend_stiffness),
            (port!(ClothParams, drag), p.drag),
            (port!(ClothParams, wind_on), p.wind_on),
            (port!(ClothParams, wind_off), p.wind_off),
            (port!(ClothParams, wind_jitter), p.wind_jitter),
        ] {
            if v < 0.0 {
                return Err(ClothError::new(name, format!("must not be negative, got {v}")));
            }
        }
        Ok(())
    }
}

impl From<ClothError> for NodeError {
    fn from(e: ClothError) -> Self {
        NodeError::port(e.param, e.message)
    }
}
