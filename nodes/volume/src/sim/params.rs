//! The parameters of a fire and smoke simulation ([`SimParams`], the ports of `volume.simulate`
//! after its inputs), the values they take at one sub-step ([`StepParams`]) and the checks no
//! port range can make.

use pyrograph_core::declare::{Anim, AnimError};
use pyrograph_core::{NodeError, port};

pyrograph_core::ports! {
    /// Every parameter of a fire and smoke simulation: the ports of `volume.simulate` after its
    /// inputs. The animated ones are sampled at every sub-step.
    #[derive(PartialEq)]
    pub struct SimParams {
        /// Edge of a voxel in world units.
        #[range(1e-4, 1e4)]
        voxel_size: f32 = 0.05,
        /// Largest distance a sub-step may carry anything, in voxels (the CFL number); more sub-steps are taken to keep to it.
        #[range(0.5, 7.0)]
        cfl: f32 = 3.0,
        /// Fewest sub-steps per frame.
        #[range(1, 64)]
        min_substeps: u32 = 1,
        /// Most sub-steps per frame (a frame whose flow would need more moves faster than `cfl`, clamped).
        #[range(1, 64)]
        max_substeps: u32 = 4,
        /// Upward acceleration per unit of temperature (Fedkiw, Stam & Jensen 2001 eq. 8, β); world units/s².
        #[range(-1e4, 1e4)]
        buoyancy: Anim<f32> = Anim::constant(2.0),
        /// Downward acceleration per unit of smoke density (eq. 8, α): heavy smoke sinks; world units/s².
        #[range(-1e4, 1e4)]
        smoke_weight: Anim<f32> = Anim::constant(0.1),
        /// Fraction of the fuel above the ignition temperature that burns per second (Nguyen, Fedkiw & Jensen 2002 §3: the reaction).
        #[range(0.0, 1e4)]
        burn_rate: Anim<f32> = Anim::constant(6.0),
        /// Temperature above which fuel burns.
        #[range(0.0, 1e4)]
        ignition: Anim<f32> = Anim::constant(0.2),
        /// Temperature released per unit of fuel burnt.
        #[range(0.0, 1e4)]
        heat: Anim<f32> = Anim::constant(1.5),
        /// Smoke released per unit of fuel burnt.
        #[range(0.0, 1e4)]
        smoke_yield: Anim<f32> = Anim::constant(0.6),
        /// Flame (the visible reaction) per unit of fuel burnt.
        #[range(0.0, 1e4)]
        flame_yield: Anim<f32> = Anim::constant(1.0),
        /// Gas expansion where fuel burns: target divergence (1/s) per unit of fuel burnt per second (Nguyen, Fedkiw & Jensen 2002 §3.1, the blue core's expansion).
        #[range(0.0, 1e3)]
        expansion: Anim<f32> = Anim::constant(0.1),
        /// Cooling: the temperature falls by this fraction per second.
        #[range(0.0, 1e4)]
        cooling: Anim<f32> = Anim::constant(0.6),
        /// The flame fades by this fraction per second (its lifespan is about 1 / flame_cooling).
        #[range(0.0, 1e4)]
        flame_cooling: Anim<f32> = Anim::constant(8.0),
        /// Smoke dissipation: the density falls by this fraction per second.
        #[range(0.0, 1e4)]
        dissipation: Anim<f32> = Anim::constant(0.05),
        /// Unburnt fuel dissipates by this fraction per second.
        #[range(0.0, 1e4)]
        fuel_dissipation: Anim<f32> = Anim::constant(1.0),
        /// Vorticity confinement ε (Fedkiw, Stam & Jensen 2001 eq. 11): restores the small swirls numerical dissipation removes.
        #[range(0.0, 100.0)]
        vorticity: Anim<f32> = Anim::constant(0.4),
        /// Turbulence: acceleration of a noise field inside the plume (world units/s²); the projection keeps its swirling part.
        #[range(0.0, 1e4)]
        turbulence: Anim<f32> = Anim::constant(1.0),
        /// Size of the turbulence's swirls in world units.
        #[range(1e-4, 1e4)]
        turbulence_scale: f32 = 0.5,
        /// How fast the turbulence changes (noise units per second).
        #[range(0.0, 1e4)]
        turbulence_speed: f32 = 0.5,
        /// How fast the air takes the wind field's velocity (1/s); 0 ignores the wind.
        #[range(0.0, 1e4)]
        wind_drag: Anim<f32> = Anim::constant(0.5),
        /// A solid ground: nothing flows below `ground_height`.
        ground: bool = false,
        /// Height of the ground.
        #[range(-1e6, 1e6)]
        ground_height: f32 = 0.0,
        /// Lower corner of the region the simulation may grow into.
        bounds_min: [f32; 3] = [-100.0, -100.0, -100.0],
        /// Upper corner of the region the simulation may grow into.
        bounds_max: [f32; 3] = [100.0, 100.0, 100.0],
        /// A brick stays active while any of its smoke, temperature, fuel or flame exceeds this (and one brick around it).
        #[range(0.0, 1e3)]
        cutoff: f32 = 0.002,
        /// The pressure solve stops when the divergence of every fluid voxel is below this (1/s).
        #[range(1e-9, 1e6)]
        tolerance: f32 = 0.01,
        /// Most conjugate-gradient iterations of a pressure solve.
        #[range(1, 100_000)]
        max_iterations: u32 = 200,
        /// Seed of the turbulence.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

/// The animated parameters' values at one sub-step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepParams {
    /// [`SimParams::buoyancy`].
    pub buoyancy: f32,
    /// [`SimParams::smoke_weight`].
    pub smoke_weight: f32,
    /// [`SimParams::burn_rate`].
    pub burn_rate: f32,
    /// [`SimParams::ignition`].
    pub ignition: f32,
    /// [`SimParams::heat`].
    pub heat: f32,
    /// [`SimParams::smoke_yield`].
    pub smoke: f32,
    /// [`SimParams::flame_yield`].
    pub flame: f32,
    /// [`SimParams::expansion`].
    pub expansion: f32,
    /// [`SimParams::cooling`].
    pub cooling: f32,
    /// [`SimParams::flame_cooling`].
    pub flame_cooling: f32,
    /// [`SimParams::dissipation`].
    pub dissipation: f32,
    /// [`SimParams::fuel_dissipation`].
    pub fuel_dissipation: f32,
    /// [`SimParams::vorticity`].
    pub vorticity: f32,
    /// [`SimParams::turbulence`].
    pub turbulence: f32,
    /// [`SimParams::wind_drag`].
    pub wind_drag: f32,
}

impl SimParams {
    /// The animated parameters at (fractional) `frame` of a clip at `fps`; errors name the port
    /// and the frame.
    pub fn at(&self, frame: f64, fps: f64) -> Result<StepParams, AnimError> {
        Ok(StepParams {
            buoyancy: self.buoyancy.at(frame, fps)?,
            smoke_weight: self.smoke_weight.at(frame, fps)?,
            burn_rate: self.burn_rate.at(frame, fps)?,
            ignition: self.ignition.at(frame, fps)?,
            heat: self.heat.at(frame, fps)?,
            smoke: self.smoke_yield.at(frame, fps)?,
            flame: self.flame_yield.at(frame, fps)?,
            expansion: self.expansion.at(frame, fps)?,
            cooling: self.cooling.at(frame, fps)?,
            flame_cooling: self.flame_cooling.at(frame, fps)?,
            dissipation: self.dissipation.at(frame, fps)?,
            fuel_dissipation: self.fuel_dissipation.at(frame, fps)?,
            vorticity: self.vorticity.at(frame, fps)?,
            turbulence: self.turbulence.at(frame, fps)?,
            wind_drag: self.wind_drag.at(frame, fps)?,
        })
    }
}

impl SimParams {
    /// Checks what no port range can (finite values, ordered bounds); errors name the port.
    pub fn validate(&self) -> Result<(), NodeError> {
        let p = self;
        let scalars = [
            (port!(SimParams, voxel_size), p.voxel_size),
            (port!(SimParams, cfl), p.cfl),
            (port!(SimParams, turbulence_scale), p.turbulence_scale),
            (port!(SimParams, turbulence_speed), p.turbulence_speed),
            (port!(SimParams, ground_height), p.ground_height),
            (port!(SimParams, cutoff), p.cutoff),
            (port!(SimParams, tolerance), p.tolerance),
        ];
        for (name, v) in scalars {
            if !v.is_finite() {
                return Err(NodeError::port(name, format!("must be finite, got {v}")));
            }
        }
        if p.voxel_size <= 0.0 {
            return Err(NodeError::port(port!(SimParams, voxel_size), format!("must be positive, got {}", p.voxel_size)));
        }
        for (name, v) in [(port!(SimParams, bounds_min), p.bounds_min), (port!(SimParams, bounds_max), p.bounds_max)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(NodeError::port(name, format!("must be finite, got {v:?}")));
            }
        }
        if (0..3).any(|k| p.bounds_max[k] <= p.bounds_min[k]) {
            return Err(NodeError::port(
                port!(SimParams, bounds_max),
                format!("must be above bounds_min {:?} on every axis, got {:?}", p.bounds_min, p.bounds_max),
            ));
        }
        if p.max_substeps < p.min_substeps {
            return Err(NodeError::port(
                port!(SimParams, max_substeps),
                format!("must be at least min_substeps ({}), got {}", p.min_substeps, p.max_substeps),
            ));
        }
        Ok(())
    }
}
