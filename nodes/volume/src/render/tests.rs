//! `volume.render` against what it must obey: Beer–Lambert attenuation of the background, shadows
//! cast through the smoke, an empty volume showing the background, and bad input as errors naming
//! the port.

use std::sync::Arc;

use glam::{IVec3, Vec3, Vec4};
use pyrograph_core::{Cook, CookCtx, Image};
use pyrograph_render::ports::CameraPorts;
use pyrograph_render::{Camera, Particle, Particles, View};

use super::compose::VolumePass;
use super::light::{Light, LightKind};
use super::march::{Look, Octaves, render};
use super::{MarchPorts, Render, no_particles};
use crate::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS, Volume};
use pyrograph_nodes_particles::types::Mesh;

const H: f64 = 0.05;

/// A volume over the bricks `lo..=hi` whose density at voxel `v` is `density(v)`.
fn volume(lo: IVec3, hi: IVec3, density: impl Fn(IVec3) -> f32) -> Volume {
    let mut coords = Vec::new();
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                coords.push(IVec3::new(x, y, z));
            }
        }
    }
    let top = Topology::new(coords);
    let mut d = vec![0.0; top.voxels()];
    for (b, c) in top.coords().iter().enumerate() {
        for i in 0..VOXELS {
            d[b * VOXELS + i] = density(*c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32));
        }
    }
    Volume {
        transform: Transform { voxel_size: H, origin: [0.0; 3] },
        topology: Arc::new(top),
        fields: vec![Field { name: "density".into(), data: FieldData::Scalar(d) }],
        time: 0.0,
        stats: SimStats::default(),
    }
}

fn look(extinction: f32) -> Look {
    Look {
        extinction,
        albedo: Vec3::splat(0.9),
        anisotropy: 0.0,
        ambient: Vec3::ZERO,
        exposure: 0.0,
        glow: 0.0,
        kelvin: [1000.0, 2600.0],
        step: 0.5,
        background: Vec4::ONE,
        seed: 7,
        octaves: Octaves::SINGLE,
    }
}

/// A camera far down +z looking along −z at world point `at`, `size` pixels square, narrow.
fn front(at: Vec3, size: u32, fov: f32) -> View {
    let camera = Camera::new(at + Vec3::Z * 40.0, at, Vec3::Y, fov, 1.0, 100.0).unwrap();
    View::new(camera, size, size).unwrap()
}

fn pixel(img: &Image, x: u32, y: u32) -> Vec4 {
    let w = img.width() as usize;
    let at = (y as usize * w + x as usize) * 4;
    Vec4::from_slice(&img.data()[at..at + 4])
}

#[test]
fn a_constant_density_attenuates_the_background_by_beer_lambert() {
    // Density 0.09375 in bricks z = 1..=4 (32 voxels deep), empty active bricks on either side so the
    // interpolated density is integrated whole: optical depth 8 × 0.09375 × 32 × 0.05 = 1.2.
    let v = volume(IVec3::new(0, 0, 0), IVec3::new(1, 1, 5), |p| if (8..40).contains(&p.z) { 0.093_75 } else { 0.0 });
    let centre = Vec3::new(8.0, 8.0, 0.0) * H as f32;
    let img = render(&v, &front(centre, 9, 2.0), &[], &look(8.0));
    let seen = pixel(&img, 4, 4);
    let want = (-1.2f32).exp();
    println!("transmittance through optical depth 1.2: {} (Beer–Lambert {want})", seen.x);
    assert!(((seen.x - want) / want).abs() < 0.01, "{} vs {want}", seen.x);
    assert!(seen.x == seen.y && seen.y == seen.z && seen.w == 1.0);
    // Twice the density: the square of the transmittance.
    let dense = volume(IVec3::new(0, 0, 0), IVec3::new(1, 1, 5), |p| if (8..40).contains(&p.z) { 0.1875 } else { 0.0 });
    let twice = pixel(&render(&dense, &front(centre, 9, 2.0), &[], &look(8.0)), 4, 4);
    assert!(((twice.x - want * want) / (want * want)).abs() < 0.02, "{} vs {}", twice.x, want * want);
}

#[test]
fn a_dense_puff_between_the_sun_and_a_thin_plume_shadows_the_plume() {
    // A thin plume around x = 8 voxels, the sun along +x, and (or not) a dense puff at x ≈ 40.
    let plume = |p: IVec3| if (p - IVec3::new(8, 8, 8)).abs().max_element() <= 3 { 0.2 } else { 0.0 };
    let puff = |p: IVec3| if (p - IVec3::new(40, 8, 8)).abs().max_element() <= 5 { 4.0 } else { 0.0 };
    let (lo, hi) = (IVec3::new(0, 0, 0), IVec3::new(6, 1, 1));
    let alone = volume(lo, hi, plume);
    let shadowed = volume(lo, hi, |p| plume(p) + puff(p));
    let mut l = look(8.0);
    l.background = Vec4::new(0.0, 0.0, 0.0, 1.0);
    let sun = [Light { kind: LightKind::Directional(Vec3::X), color: Vec3::splat(3.0) }];
    // Looking at the plume only (the puff is out of the narrow view).
    let view = front(Vec3::splat(8.0 * H as f32), 5, 1.0);
    let lit = pixel(&render(&alone, &view, &sun, &l), 2, 2);
    let dark = pixel(&render(&shadowed, &view, &sun, &l), 2, 2);
    println!("the plume lit {} and in the puff's shadow {}", lit.x, dark.x);
    assert!(lit.x > 0.02, "the sun lights the plume: {lit}");
    assert!(dark.x < 0.05 * lit.x, "the puff's shadow: {dark} against {lit}");
}

#[test]
fn skipping_bricks_with_nothing_in_them_loses_no_light() {
    // Smoke filling brick x = 1 exactly, so its neighbours x = 0 and 2 hold nothing themselves
    // but their samples near the shared faces read it; bricks x = 3..5 hold nothing at all.
    let slab = |p: IVec3| if (8..16).contains(&p.x) { 0.5 } else { 0.0 };
    let (lo, hi) = (IVec3::new(0, 0, 0), IVec3::new(5, 1, 1));
    let skipped = volume(lo, hi, slab);
    // The same smoke over a trace of density everywhere, so no brick is skipped: every extra
    // sample adds ~1e-38 of absorption and light.
    let marched = volume(lo, hi, |p| slab(p) + 1e-37);
    let mut l = look(8.0);
    l.background = Vec4::new(0.1, 0.1, 0.1, 1.0);
    l.ambient = Vec3::splat(0.3);
    let lights = [
        Light { kind: LightKind::Directional(Vec3::new(1.0, 0.3, 0.2).normalize()), color: Vec3::splat(3.0) },
        Light { kind: LightKind::Point(Vec3::new(20.0, 8.0, 8.0) * H as f32), color: Vec3::splat(0.05) },
    ];
    // Looking across x, so rays cross the faces of brick 1 at a slant.
    let at = Vec3::new(12.0, 8.0, 8.0) * H as f32;
    let camera = Camera::new(at + Vec3::new(1.0, 0.4, 2.0), at, Vec3::Y, 30.0, 0.1, 100.0).unwrap();
    let view = View::new(camera, 24, 16).unwrap();
    let (a, b) = (render(&skipped, &view, &lights, &l), render(&marched, &view, &lights, &l));
    let worst = a.data().iter().zip(b.data()).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    let lit = a.data().chunks(4).filter(|p| p[0] > 0.11).count();
    assert!(lit > 20, "the slab is seen: {lit} pixels brighter than the background");
    assert!(worst < 1e-6, "skipped and marched renders differ by {worst}");
}

#[test]
fn an_empty_volume_renders_the_background() {
    let v = Volume::empty(H);
    let mut l = look(8.0);
    l.background = Vec4::new(0.2, 0.3, 0.4, 1.0);
    let img = render(&v, &front(Vec3::ZERO, 6, 30.0), &[], &l);
    assert!(img.data().chunks(4).all(|p| p == [0.2, 0.3, 0.4, 1.0]));
}

/// The march ports with `exposure` and `glow`, extinction 8, step half a voxel.
fn march(exposure: f32, glow: f32) -> MarchPorts {
    MarchPorts {
        extinction: 8.0,
        exposure,
        glow,
        kelvin_cold: 1000.0,
        kelvin_hot: 2600.0,
        step_size: 0.5,
        ..MarchPorts::default()
    }
}

fn node(v: Volume) -> Render {
    Render {
        volume: Arc::new(v),
        lights: no_particles(),
        flames: no_particles(),
        sparks: no_particles(),
        flame_exposure: pyrograph_nodes_particles::swept::Exposure::Continuous,
        camera: CameraPorts::looking(16, 9, [0.4, 0.4, 6.0], [0.4, 0.4, 0.0]),
        march: march(8.0, 0.1),
        albedo: [0.85; 3],
        anisotropy: 0.3,
        ambient: [0.05; 3],
        sun_direction: [0.5, 1.0, 0.3],
        sun_color: [1.0; 3],
        fire_light: 1.0,
        background: [0.0, 0.0, 0.0, 1.0],
        mesh: Arc::new(Mesh::default()),
        mesh_color: [0.5, 0.5, 0.5, 1.0],
        pass: VolumePass::Beauty,
        frame_rate: 24.0,
    }
}

#[test]
fn bad_lights_directions_and_densities_are_errors_naming_the_port() {
    let blob = || volume(IVec3::ZERO, IVec3::ONE, |p| if p.x < 4 { 0.5 } else { 0.0 });
    let ctx = CookCtx::new();
    let mut n = node(blob());
    n.lights = Arc::new(Particles {
        particles: vec![Particle { position: [0.0, f32::NAN, 0.0], weight: 1.0, ..Particle::default() }],
        ..Particles::default()
    });
    let e = n.cook(&ctx).expect_err("a NaN light is refused").to_string();
    assert!(e.contains("lights") && e.contains("light 0"), "{e}");
    let mut n = node(blob());
    n.sun_direction = [0.0; 3];
    let e = n.cook(&ctx).expect_err("no sun direction").to_string();
    assert!(e.contains("sun_direction"), "{e}");
    let e = node(volume(IVec3::ZERO, IVec3::ONE, |p| if p.x == 3 { -0.5 } else { 0.0 })).cook(&ctx).expect_err("negative");
    assert!(e.to_string().contains("volume") && e.to_string().contains("negative"), "{e}");
    let mut bad = square(0.0, 1.0);
    bad.triangles[1] = [0, 2, 9];
    let e = Render { mesh: Arc::new(bad), ..node(blob()) }.cook(&ctx).expect_err("a bad triangle").to_string();
    assert!(e.contains("mesh") && e.contains("triangle 1"), "{e}");
    let out = node(blob()).cook(&ctx).expect("a good volume renders");
    assert_eq!((out.width(), out.height()), (16, 9));
}

/// A square at depth `z` facing +z, `half` wide each way, as two triangles.
fn square(z: f32, half: f32) -> Mesh {
    let c = Vec3::new(0.4, 0.4, z);
    let corner = |x: f32, y: f32| (c + Vec3::new(x, y, 0.0) * half).to_array();
    Mesh {
        positions: vec![corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        normals: vec![[0.0, 0.0, 1.0]; 2],
        ..Mesh::default()
    }
}

/// The Beer–Lambert slab of the first test (optical depth 1.2 along z, world z 0.4..2.0), seen
/// head on by [`node`]'s camera, smoke that only absorbs, and a mesh lit by a white ambient light.
fn slab_node(mesh: Mesh) -> Render {
    let v = volume(IVec3::new(0, 0, 0), IVec3::new(1, 1, 5), |p| if (8..40).contains(&p.z) { 0.093_75 } else { 0.0 });
    Render {
        mesh: Arc::new(mesh),
        albedo: [0.0; 3],
        ambient: [1.0; 3],
        sun_color: [0.0; 3],
        fire_light: 0.0,
        march: march(0.0, 0.0),
        ..node(v)
    }
}

#[test]
fn a_mesh_in_front_hides_the_volume_and_one_behind_is_attenuated_by_it() {
    let ctx = CookCtx::new();
    let centre = |n: Render| pixel(&n.cook(&ctx).unwrap(), 8, 4);
    // Lit by the ambient light alone: albedo × 1.
    let front = centre(slab_node(square(4.0, 3.0)));
    assert_eq!(front, Vec4::new(0.5, 0.5, 0.5, 1.0), "the mesh in front, untouched by the smoke behind it");
    let behind = centre(slab_node(square(-0.5, 3.0)));
    let want = 0.5 * (-1.2f32).exp();
    println!("a mesh behind optical depth 1.2: {} (0.5 × Beer–Lambert {want})", behind.x);
    assert!(((behind.x - want) / want).abs() < 0.01 && behind.w == 1.0, "{behind} vs {want}");
    // The depth pass: where the smoke's opacity reaches one half (optical depth ln 2, 0.924 into
    // the slab from its near face at z = 2), or the mesh in front of it.
    let depth = |n: Render| n.cook(&ctx).unwrap().pixel(8, 4)[0];
    let smoke = depth(Render { pass: VolumePass::Depth, ..slab_node(Mesh::default()) });
    let want = 6.0 - (2.0 - 2f32.ln() / 1.2 * 1.6);
    assert!((smoke - want).abs() < 0.03, "smoke depth {smoke} vs {want}");
    let wall = depth(Render { pass: VolumePass::Depth, ..slab_node(square(4.0, 3.0)) });
    assert!((wall - 2.0).abs() < 1e-3, "mesh depth {wall}");
}

#[test]
fn the_passes_split_the_beauty_into_emission_and_scattering() {
    // A glowing, lit blob: beauty = scattering + emission over the black background.
    let mut v = volume(IVec3::ZERO, IVec3::ONE, |p| if (p - IVec3::splat(8)).abs().max_element() <= 4 { 0.3 } else { 0.0 });
    let flame = v.scalar("density").unwrap().iter().map(|d| d * 2.0).collect();
    v.fields.push(Field { name: "flame".into(), data: FieldData::Scalar(flame) });
    let ctx = CookCtx::new();
    let camera = CameraPorts::looking(32, 24, [0.4, 0.4, 2.0], [0.4, 0.4, 0.4]);
    let cook = |pass| Render { pass, camera: camera.clone(), ..node(v.clone()) }.cook(&ctx).unwrap();
    let (beauty, emission, scattering) = (cook(VolumePass::Beauty), cook(VolumePass::Emission), cook(VolumePass::Scattering));
    let premultiplied = |img: &Image, x, y| {
        let p = pixel(img, x, y);
        p.truncate() * p.w
    };
    let mut lit = 0;
    for y in 0..24 {
        for x in 0..32 {
            let (b, e, s) = (premultiplied(&beauty, x, y), premultiplied(&emission, x, y), premultiplied(&scattering, x, y));
            assert!((b - (e + s)).abs().max_element() <= 1e-4 * b.max_element().max(1.0), "({x}, {y}): {b} vs {e} + {s}");
            lit += usize::from(e.x > 0.0 && s.x > 0.0);
        }
    }
    assert!(lit > 40, "the blob both glows and scatters in {lit} pixels");
    let alpha = cook(VolumePass::Alpha);
    assert_eq!(alpha.channels(), pyrograph_core::Channels::Gray);
    assert!(alpha.data().iter().all(|a| *a == 1.0), "over an opaque background the beauty is opaque");
}

#[test]
fn the_motion_pass_projects_the_smokes_velocity_to_pixels_per_frame() {
    let mut v = volume(IVec3::ZERO, IVec3::ONE, |p| if (p - IVec3::splat(8)).abs().max_element() <= 5 { 0.5 } else { 0.0 });
    let n = v.topology.voxels();
    v.fields.push(Field { name: "vel".into(), data: FieldData::Vector(vec![[1.2, 0.0, 0.0]; n]) });
    let n = Render { pass: VolumePass::Motion, frame_rate: 24.0, ..node(v) };
    let view = n.camera.view().unwrap();
    let img = n.cook(&CookCtx::new()).unwrap();
    let m = pixel(&img, 8, 4);
    // The blob's centre (0.4, 0.4, 0.4) moves 1.2 / 24 world units along +x in a frame.
    let at = Vec3::splat(0.4);
    let want = view.project(at + Vec3::X * 0.05).unwrap().x - view.project(at).unwrap().x;
    println!("motion {m} vs {want} pixels per frame");
    assert!((m.x - want).abs() < 0.05 * want && m.y.abs() < 0.02 * want && m.w > 0.5, "{m} vs {want}");
    assert_eq!(pixel(&img, 0, 0), Vec4::ZERO, "no smoke, no motion");
}

/// One additive flame particle at `z` on the slab's axis, `half` wide, in front of the camera of [`node`].
fn flame_at(z: f32) -> Arc<Particles> {
    let q = Particle {
        position: [0.4, 0.4, z],
        size: [0.3, 0.3],
        center: [0.6, 0.4, 0.2, 0.9],
        edge: [0.6, 0.4, 0.2, 0.0],
        ..Particle::default()
    };
    Arc::new(Particles { particles: vec![q], sides: 8, ..Particles::default() })
}

#[test]
fn flames_inside_the_smoke_are_dimmed_by_the_smoke_in_front_of_them_and_hidden_by_the_mesh() {
    let ctx = CookCtx::new();
    // The slab absorbs only; its twin holds the same bricks and no smoke.
    let clear = || {
        let mut n = slab_node(Mesh::default());
        let mut v = (*n.volume).clone();
        v.fields[0].data = FieldData::Scalar(vec![0.0; v.topology.voxels()]);
        n.volume = Arc::new(v);
        n
    };
    let centre = |n: Render| pixel(&n.cook(&ctx).unwrap(), 8, 4);
    // Behind the slab (world z 0.4..2.0, optical depth 1.2): dimmed by Beer–Lambert.
    let seen = centre(Render { flames: flame_at(-0.5), ..slab_node(Mesh::default()) });
    let bare = centre(Render { flames: flame_at(-0.5), ..clear() });
    let want = (-1.2f32).exp();
    println!("a flame behind optical depth 1.2: {seen} against {bare} without smoke (Beer–Lambert {want})");
    assert!(bare.x > 0.03, "the flame is seen: {bare}");
    for k in 0..3 {
        assert!(((seen[k] / bare[k] - want) / want).abs() < 0.01, "channel {k}: {seen} / {bare} vs {want}");
    }
    // In front of the slab: untouched by the smoke behind it.
    let front = centre(Render { flames: flame_at(3.0), ..slab_node(Mesh::default()) });
    let alone = centre(Render { flames: flame_at(3.0), ..clear() });
    assert!((front - alone).abs().max_element() < 1e-6 && front.x > 0.03, "{front} vs {alone}");
    // Sparks are dimmed the same way.
    let sparks = centre(Render { sparks: flame_at(-0.5), ..slab_node(Mesh::default()) });
    assert!((sparks - seen).abs().max_element() < 1e-6, "{sparks} vs {seen}");
    // A mesh in front hides the flame; one behind it is seen with it, both dimmed by the smoke.
    let hidden = centre(Render { flames: flame_at(-0.5), ..slab_node(square(4.0, 3.0)) });
    assert_eq!(hidden, Vec4::new(0.5, 0.5, 0.5, 1.0), "the flame behind the mesh");
    let over = centre(Render { flames: flame_at(-0.5), ..slab_node(square(-1.0, 3.0)) });
    let sum = bare.truncate() * want + Vec3::splat(0.5 * want);
    assert!((over.truncate() - sum).abs().max_element() < 0.01 * sum.max_element(), "{over} vs {sum}");
    // The flame is light: in the emission pass, and in the alpha over a clear background.
    let emission = centre(Render { flames: flame_at(-0.5), pass: VolumePass::Emission, ..slab_node(Mesh::default()) });
    assert!((emission.truncate() * emission.w - seen.truncate()).abs().max_element() < 1e-5, "{emission} vs {seen}");
    let alpha = |flames| {
        let n = Render { flames, pass: VolumePass::Alpha, background: [0.0; 4], ..clear() };
        n.cook(&ctx).unwrap().pixel(8, 4)[0]
    };
    assert!(alpha(no_particles()) == 0.0 && alpha(flame_at(-0.5)) > 0.05, "the flame's coverage");
}

#[test]
fn a_flame_particle_with_a_nan_is_an_error_naming_the_port() {
    let mut bad = (*flame_at(0.0)).clone();
    bad.particles[0].size[1] = f32::NAN;
    let n = Render { sparks: Arc::new(bad), ..slab_node(Mesh::default()) };
    let e = n.cook(&CookCtx::new()).expect_err("a NaN size is refused").to_string();
    assert!(e.contains("sparks") && e.contains("particle 0"), "{e}");
}

#[test]
fn scattering_octaves_lift_the_shadowed_smoke_more_than_the_lit_smoke() {
    // The plume and puff of the shadow test, lit by the sun along +x, seen with 1 and 4 octaves.
    let plume = |p: IVec3| if (p - IVec3::new(8, 8, 8)).abs().max_element() <= 3 { 0.2 } else { 0.0 };
    let puff = |p: IVec3| if (p - IVec3::new(40, 8, 8)).abs().max_element() <= 5 { 4.0 } else { 0.0 };
    let (lo, hi) = (IVec3::new(0, 0, 0), IVec3::new(6, 1, 1));
    let (alone, shadowed) = (volume(lo, hi, plume), volume(lo, hi, |p| plume(p) + puff(p)));
    let sun = [Light { kind: LightKind::Directional(Vec3::X), color: Vec3::splat(3.0) }];
    let view = front(Vec3::splat(8.0 * H as f32), 5, 1.0);
    let seen = |v: &Volume, octaves: Octaves| {
        let l = Look { background: Vec4::new(0.0, 0.0, 0.0, 1.0), octaves, ..look(8.0) };
        pixel(&render(v, &view, &sun, &l), 2, 2).x
    };
    let four = Octaves { count: 4, albedo: 0.5, extinction: 0.5, anisotropy: 0.5 };
    let (lit, lit4) = (seen(&alone, Octaves::SINGLE), seen(&alone, four));
    let (dark, dark4) = (seen(&shadowed, Octaves::SINGLE), seen(&shadowed, four));
    println!("lit plume {lit} → {lit4}; shadowed {dark} → {dark4}");
    // Isotropic phase: octave i adds 0.5^i of single scattering through thinner shadows, so at least 0.5^i of it.
    assert!(lit4 >= lit * 1.875 * 0.999, "{lit4} vs {lit}");
    assert!(dark4 / dark > 2.0 * (lit4 / lit), "the shadow opens up: {dark} → {dark4} against {lit} → {lit4}");
    assert!(dark4 < lit4, "still in shadow: {dark4} vs {lit4}");
}

#[test]
fn octaves_sum_their_shares_through_thinned_shadows() {
    let o = Octaves { count: 3, albedo: 0.5, extinction: 0.25, anisotropy: 0.5 };
    let p = o.phases(0.3, 0.6);
    let hg = super::light::henyey_greenstein;
    assert_eq!(p[0], hg(0.3, 0.6));
    assert!((p[1] - 0.5 * hg(0.3, 0.3)).abs() < 1e-7 && (p[2] - 0.25 * hg(0.3, 0.15)).abs() < 1e-7, "{p:?}");
    assert!(p[3..].iter().all(|x| *x == 0.0));
    let t = (-4.0f32).exp();
    let want = p[0] * t + p[1] * (-1.0f32).exp() + p[2] * (-0.25f32).exp();
    assert!((o.through(&p, t) - want).abs() < 1e-6, "{} vs {want}", o.through(&p, t));
    assert_eq!(o.through(&p, 0.0), 0.0);
    assert_eq!(Octaves::SINGLE.through(&Octaves::SINGLE.phases(0.3, 0.6), t), hg(0.3, 0.6) * t);
}

#[test]
fn an_octave_scattering_more_than_it_lets_through_is_an_error() {
    let mut n = slab_node(Mesh::default());
    n.march.scattering_octaves = 3;
    n.march.octave_albedo = 0.8;
    let e = n.cook(&CookCtx::new()).expect_err("a glowing octave is refused").to_string();
    assert!(e.contains("octave_albedo") && e.contains("octave_extinction"), "{e}");
}
