//! pyrograph-nodes-particles: Perry's particle flames (Perry 1994, "A Model for Fire Spread",
//! ch. 3): wind fields (§3.2.3), flame roots, particle flames as long-exposure particle
//! trajectories (§3.2.1–3.2.2), their rendering through a camera, and per-flame lights (§3.2.4).
//! The algorithms are plain functions ([`flame::simulate_frame`], [`render::render_particles`],
//! [`wind::WindSampler`], [`render::flame_lights`]); the node wrappers only read ports.
#![deny(missing_docs)]

pub mod char_marks;
pub mod embers;
pub mod fire;
pub mod flame;
pub mod lit_mesh;
pub mod mesh;
pub mod mesh_roots;
pub mod passes;
pub mod render;
pub mod spread;
pub mod swept;
pub mod types;
pub mod usd;
pub mod wind;

use pyrograph_core::Registry;

/// Adds every particle node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<wind::WindFieldNode>();
    registry.declare::<flame::Roots>();
    registry.declare::<flame::ParticleFlame>();
    registry.declare::<render::RenderFlames>();
    registry.declare::<render::FlameLights>();
    registry.declare::<mesh::MeshLoad>();
    registry.declare::<spread::FireSpread>();
    registry.declare::<char_marks::Char>();
    registry.declare::<fire::RenderFire>();
    registry.declare::<mesh_roots::MeshRoots>();
    registry.declare::<embers::Embers>();
    registry.declare::<usd::WriteUsd>();
}

#[cfg(test)]
mod tests {
    use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, PortType, Registry, Value};

    #[test]
    fn a_flame_graph_lifts_the_renderer_into_a_clip_of_images() {
        let mut registry = Registry::with_builtins();
        super::register(&mut registry);
        let doc = GraphDoc::from_ron(
            r#"(version: 1, nodes: {
                "roots": (type: "particles.roots", params: {"count": 3}),
                "wind": (type: "particles.wind_field", params: {"k_p": 0.5}),
                "flames": (type: "particles.particle_flame", params: {"frames": 4}),
                "lights": (type: "particles.flame_lights"),
                "render": (type: "particles.render_flames", params: {"width": 32, "height": 24, "ground": true}),
            }, edges: [
                ("roots.roots", "flames.roots"), ("wind.wind", "flames.wind"), ("flames.flames", "lights.flames"),
                ("flames.flames", "render.flames"), ("lights.lights", "render.lights"),
            ])"#,
        )
        .unwrap();
        let graph = Graph::build(&doc, &registry, std::path::Path::new("."), &BuildOptions::default()).unwrap();
        let Value::Clip(clip) = Evaluator::new().output(&graph, "render.image", &CookCtx::new()).unwrap() else {
            panic!("render_flames over a clip of flames gives a clip")
        };
        assert_eq!((clip.len(), clip.element()), (4, &PortType::Image));
        let img = clip.image(3, &CookCtx::new()).unwrap();
        assert_eq!(img.size(), (32, 24));
        assert!(img.data().chunks(4).any(|p| p[0] > 0.5), "some flame pixels are bright");
    }

    #[test]
    fn bad_meshes_and_ignitions_are_errors_naming_the_node_file_line_and_port() {
        let dir = std::env::temp_dir().join(format!("pyrograph-bad-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("garbled.obj"), "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 1 x 0\nf 1 2 3\n").unwrap();
        std::fs::write(dir.join("points.obj"), "v 0 0 0\nv 1 0 0\nv 1 0 1\n").unwrap();
        std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
        let mut registry = Registry::with_builtins();
        super::register(&mut registry);
        let doc = GraphDoc::from_ron(
            r#"(version: 1, nodes: {
                "garbled": (type: "particles.mesh_load", params: {"source": "obj", "path": "garbled.obj"}),
                "points": (type: "particles.mesh_load", params: {"source": "obj", "path": "points.obj"}),
                "flat": (type: "particles.mesh_load", params: {"source": "obj", "path": "flat.obj"}),
                "cube": (type: "particles.mesh_load", params: {"source": "cube"}),
                "spread": (type: "particles.fire_spread", params: {"ignite": "0.5 0.1 0; 3 0 0"}),
            }, edges: [("cube.mesh", "spread.mesh")])"#,
        )
        .unwrap();
        let graph = Graph::build(&doc, &registry, &dir, &BuildOptions::default()).unwrap();
        let error = |endpoint: &str| match Evaluator::new().output(&graph, endpoint, &CookCtx::new()) {
            Ok(_) => panic!("{endpoint} cooked without an error"),
            Err(e) => e.to_string(),
        };
        let e = error("garbled.mesh");
        assert!(e.contains("port 'path'") && e.contains("garbled.obj") && e.contains("line 4") && e.contains("1 x 0"), "{e}");
        let e = error("points.mesh");
        assert!(e.contains("points.obj") && e.contains("no faces"), "{e}");
        let e = error("flat.mesh");
        assert!(e.contains("flat.obj") && e.contains("face 1 is degenerate"), "{e}");
        let e = error("spread.spread");
        assert!(e.contains("port 'ignite'") && e.contains("point 2 at (3, 0, 0) is off the mesh"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
