//! pyrograph-nodes-particles: Perry's particle flames (Perry 1994, "A Model for Fire Spread",
//! ch. 3): wind fields (§3.2.3), flame roots, particle flames as long-exposure particle
//! trajectories (§3.2.1–3.2.2), their rendering through a camera, and per-flame lights (§3.2.4).
//! The algorithms are plain functions ([`flame::simulate_frame`], [`render::render_particles`],
//! [`wind::WindSampler`], [`render::flame_lights`]); the node wrappers only read ports.
#![deny(missing_docs)]

pub mod char;
pub mod fire;
pub mod flame;
pub mod mesh;
pub mod render;
pub mod spread;
pub mod wind;

use pyrograph_core::Registry;

/// Adds every particle node type.
pub fn register(registry: &mut Registry) {
    wind::register(registry);
    flame::register(registry);
    render::register(registry);
    mesh::register(registry);
    spread::register(registry);
    char::register(registry);
    fire::register(registry);
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
}
