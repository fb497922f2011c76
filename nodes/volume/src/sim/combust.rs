//! Combustion, cooling and dissipation per voxel (Nguyen, Fedkiw & Jensen 2002 §3, as a
//! grid reaction the way Houdini's Pyro and EmberGen model it): fuel hotter than the ignition
//! temperature burns at `burn_rate`, releasing heat, smoke and flame and expanding the gas;
//! temperature, flame, smoke and unburnt fuel then decay exponentially.

use rayon::prelude::*;

use super::params::StepParams;
use super::state::SimState;
use crate::grid::VOXELS;

/// One brick of density, temperature, fuel and flame.
type Bricks<'a> = (((&'a mut [f32], &'a mut [f32]), &'a mut [f32]), &'a mut [f32]);

/// Burns and cools over `dt` seconds; returns the expansion each voxel asks of the pressure
/// projection (1/s), empty when the expansion is 0.
pub fn combust(state: &mut SimState, p: &StepParams, dt: f32) -> Vec<f32> {
    let burn = 1.0 - (-p.burn_rate * dt).exp();
    let decay = |rate: f32| (-rate * dt).exp();
    let (cool, flame_cool, dissipate, fuel_loss) =
        (decay(p.cooling), decay(p.flame_cooling), decay(p.dissipation), decay(p.fuel_dissipation));
    let expanding = p.expansion > 0.0;
    let mut target = if expanding { vec![0.0; state.top.voxels()] } else { Vec::new() };
    // In the order of `state::DENSITY`, `TEMPERATURE`, `FUEL` and `FLAME`.
    let [density, temperature, fuel, flame] = &mut state.scalars;
    let chunks = density
        .par_chunks_mut(VOXELS)
        .zip(temperature.par_chunks_mut(VOXELS))
        .zip(fuel.par_chunks_mut(VOXELS))
        .zip(flame.par_chunks_mut(VOXELS));
    let per_brick = |(((d, t), f), fl): Bricks, mut out: Option<&mut [f32]>| {
        for i in 0..VOXELS {
            let burnt = if t[i] > p.ignition && f[i] > 0.0 { f[i] * burn } else { 0.0 };
            f[i] = (f[i] - burnt) * fuel_loss;
            t[i] = (t[i] + burnt * p.heat) * cool;
            d[i] = (d[i] + burnt * p.smoke) * dissipate;
            fl[i] = (fl[i] * flame_cool).max(burnt * p.flame / (burn.max(1e-6)));
            if let Some(o) = out.as_deref_mut() {
                o[i] = p.expansion * burnt / dt;
            }
        }
    };
    if expanding {
        chunks.zip(target.par_chunks_mut(VOXELS)).for_each(|(c, o)| per_brick(c, Some(o)));
    } else {
        chunks.for_each(|c| per_brick(c, None));
    }
    target
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Topology;
    use crate::sim::SimParams;
    use crate::sim::state::{DENSITY, FLAME, FUEL, TEMPERATURE};
    use glam::IVec3;
    use std::sync::Arc;

    fn one_brick(temperature: f32, fuel: f32) -> SimState {
        let mut s = SimState::new(0.1);
        s.top = Arc::new(Topology::new(vec![IVec3::ZERO]));
        s.scalars = [vec![0.0; VOXELS], vec![temperature; VOXELS], vec![fuel; VOXELS], vec![0.0; VOXELS]];
        s
    }

    #[test]
    fn hot_fuel_burns_into_heat_smoke_and_flame_and_cold_fuel_does_not() {
        let p = SimParams::default().at(0.0, 24.0).unwrap();
        let mut hot = one_brick(1.0, 1.0);
        let target = combust(&mut hot, &p, 0.05);
        let burnt = 1.0 - (-p.burn_rate * 0.05f32).exp();
        assert!((hot.scalars[FUEL][0] - (1.0 - burnt) * (-p.fuel_dissipation * 0.05f32).exp()).abs() < 1e-6);
        assert!(hot.scalars[DENSITY][0] > 0.0 && hot.scalars[FLAME][0] > 0.0);
        assert!(hot.scalars[TEMPERATURE][0] > 1.0 * (-p.cooling * 0.05f32).exp(), "the burning adds heat");
        assert!(target[0] > 0.0, "burning gas expands");
        let mut cold = one_brick(0.0, 1.0);
        combust(&mut cold, &p, 0.05);
        assert_eq!((cold.scalars[DENSITY][0], cold.scalars[FLAME][0]), (0.0, 0.0));
    }
}
