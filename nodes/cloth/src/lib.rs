//! pyrograph-nodes-cloth: mass-spring flames, the "silk torch" of the mass-spring flame project
//! 2019 (after Balci & Foroosh 2006): each flame is a cloth of masses joined by Hooke springs
//! (§Internal Forces), with optional shear and bend springs (Provot 1995), pinned along its
//! bottom row, pushed up by buoyancy and sideways by impulses of wind (§External Forces),
//! integrated with semi-implicit Euler in sub-steps (§Integration), and drawn as a textured,
//! camera-facing mesh (§Textures).
//!
//! The algorithms are plain functions and types ([`sim::Simulation`], [`sim::Topology`],
//! [`render::render_cloth`], [`textures::builtin_textures`]); the node wrappers only read ports.
//!
//! Nodes: `cloth.mass_spring_flame` (simulation, a clip of [`ClothState`]),
//! `cloth.cloth_render` (built-in procedural flame textures, wireframe, plain cloth) and
//! `cloth.cloth_render_textured` (the same with a required texture input, so any image or clip —
//! another node's output — textures the cloth; a `Clip<Image>` there lifts the render over time
//! together with the cloth clip), `cloth.write_usd` (the cloths as an animated USD mesh).
#![deny(missing_docs)]

pub mod render;
pub mod sim;
pub mod state;
pub mod stencil;
pub mod textures;
pub mod usd;

use pyrograph_core::Registry;

/// Adds every cloth node type.
pub fn register(registry: &mut Registry) {
    registry.declare::<sim::MassSpringFlame>();
    registry.declare::<render::ClothRender>();
    registry.declare::<render::ClothRenderTextured>();
    registry.declare::<usd::WriteClothUsd>();
}

#[cfg(test)]
mod tests {
    use crate::state::ClothState;
    use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, PortType, Registry, Value};

    fn cook(ron: &str, endpoint: &str) -> Value {
        let mut registry = Registry::with_builtins();
        super::register(&mut registry);
        pyrograph_nodes_imaging::register(&mut registry);
        let doc = GraphDoc::from_ron(ron).unwrap();
        let graph = Graph::build(&doc, &registry, std::path::Path::new("."), &BuildOptions::default()).unwrap();
        Evaluator::new().output(&graph, endpoint, &CookCtx::new()).unwrap()
    }

    #[test]
    fn a_cloth_graph_lifts_the_renderer_into_a_clip_of_images() {
        let v = cook(
            r#"(version: 1, nodes: {
                "cloth": (type: "cloth.mass_spring_flame", params: {"count": 4, "frames": 6, "grid_width": 6, "grid_height": 10}),
                "render": (type: "cloth.cloth_render", params: {"width": 48, "height": 32}),
            }, edges: [("cloth.cloth", "render.cloth")])"#,
            "render.image",
        );
        let Value::Clip(clip) = v else { panic!("a clip of cloth states lifts the renderer") };
        assert_eq!((clip.len(), clip.element()), (6, &PortType::Image));
        let img = clip.image(5, &CookCtx::new()).unwrap();
        assert_eq!(img.size(), (48, 32));
        assert!(img.data().chunks(4).any(|p| p[0] > 0.5), "some flame pixels are bright");
    }

    #[test]
    fn a_texture_clip_from_another_node_textures_the_cloth_frame_by_frame() {
        let ron = r#"(version: 1, nodes: {
                "tex": (type: "imaging.turbulence_flame", params: {"width": 16, "height": 32, "frames": 4, "seed": 2}),
                "cloth": (type: "cloth.mass_spring_flame", params: {"count": 1, "frames": 5, "grid_width": 4, "grid_height": 6}),
                "render": (type: "cloth.cloth_render_textured", params: {"width": 40, "height": 40, "camera_position": (0.0, 1.0, 5.0)}),
            }, edges: [("cloth.cloth", "render.cloth"), ("tex.clip", "render.texture")])"#;
        let Value::Clip(clip) = cook(ron, "render.image") else { panic!("the render is lifted over both clips") };
        // Lifted over both clips: as long as the shorter one.
        assert_eq!((clip.len(), clip.element()), (4, &PortType::Image));
        let ctx = CookCtx::new();
        let (a, b) = (clip.image(1, &ctx).unwrap(), clip.image(3, &ctx).unwrap());
        assert!(a.data().chunks(4).any(|p| p[0] > 0.3), "the textured cloth is visible");
        assert_ne!(a.data(), b.data(), "frames differ as cloth and texture move");
        let Value::Clip(states) = cook(ron, "cloth.cloth") else { panic!("the simulation gives a clip") };
        let Some(s) = states.get(2, &ctx).unwrap().downcast::<ClothState>() else { panic!("cloth states") };
        assert_eq!((s.flames(), s.width, s.height, s.positions.len()), (1, 4, 6, 24));
    }
}
