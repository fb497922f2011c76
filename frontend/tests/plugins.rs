//! Python plugin nodes cooked through the Rust API: pixels cross to Python and back exactly,
//! the frames of a clip cook on several workers, results are cached by the plugin file's
//! content, and a broken plugin is an error naming its file and line. Needs a Python with numpy.

use std::path::Path;

use pyrograph_frontend::core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, Registry, Value};
use pyrograph_frontend::plugin::discover::PluginDir;
use pyrograph_frontend::plugin::{PluginOptions, extend};
use rayon::prelude::*;

fn registry_with(dir: &Path, workers: usize) -> Registry {
    let mut registry = pyrograph_frontend::registry();
    let mut options = PluginOptions::new(vec![PluginDir { path: dir.to_path_buf(), origin: "--plugins" }]);
    options.python = pyrograph_testing::python_with_numpy();
    options.workers = workers;
    extend(&mut registry, &options).unwrap();
    registry
}

const OFFSET: &str = r#"
import os
import time
import numpy as np
from pyrograph_plugin import node, Image, Mask, Float, Int, Outputs

@node("studio.offset", category="Studio")
def offset(image: Image(doc="In"), amount: Float(range=(-10.0, 10.0)) = 0.25) -> Outputs(image=Image(), mask=Mask(), pid=Int()):
    """Adds amount to every sample; the mask is where the first channel is over one half."""
    first = image if image.ndim == 2 else image[..., 0]
    time.sleep(0.05)  # long enough that two frames cooking at once need two workers
    return image + np.float32(amount), first > 0.5, os.getpid()
"#;

fn graph(registry: &Registry, ron: &str) -> Graph {
    let doc = GraphDoc::from_ron(ron).unwrap();
    Graph::build(&doc, registry, Path::new("."), &BuildOptions::default()).unwrap()
}

const FLAME_OFFSET: &str = r#"(version: 1, nodes: {
    "flame": (type: "imaging.turbulence_flame", params: {"width": 48, "height": 64, "frames": 6}),
    "off": (type: "studio.offset", params: {"amount": 0.5}),
}, edges: [("flame.clip", "off.image")])"#;

fn frames(value: Value, ctx: &CookCtx) -> Vec<Value> {
    let Value::Clip(clip) = value else { panic!("not a clip: {value:?}") };
    (0..clip.len()).into_par_iter().map(|i| clip.get(i, ctx).unwrap()).collect()
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn pixels_cross_to_python_and_back_exactly_on_several_workers() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("offset.py"), OFFSET).unwrap();
    let registry = registry_with(dir.path(), 2);
    let g = graph(&registry, FLAME_OFFSET);
    let ctx = CookCtx::new();
    let mut ev = Evaluator::new();
    let flames = frames(ev.output(&g, "flame.clip", &ctx).unwrap(), &ctx);
    let shifted = frames(ev.output(&g, "off.image", &ctx).unwrap(), &ctx);
    let masks = frames(ev.output(&g, "off.mask", &ctx).unwrap(), &ctx);
    let pids = frames(ev.output(&g, "off.pid", &ctx).unwrap(), &ctx);
    assert_eq!(shifted.len(), 6);
    for ((flame, out), mask) in flames.iter().zip(&shifted).zip(&masks) {
        let (Value::Image(a), Value::Image(b), Value::Mask(m)) = (flame, out, mask) else { panic!() };
        assert_eq!((b.size(), b.channels()), (a.size(), a.channels()));
        assert!(a.data().iter().zip(b.data()).all(|(x, y)| x + 0.5 == *y), "every sample plus 0.5, in place");
        let over: Vec<u8> = a.data().chunks(a.channels().count()).map(|p| if p[0] > 0.5 { 255 } else { 0 }).collect();
        assert_eq!(m.data(), over.as_slice());
        assert!(over.contains(&255) && over.contains(&0), "the test image has both sides of the threshold");
    }
    let mut workers: Vec<i64> = pids.iter().map(|p| if let Value::Int(i) = p { *i } else { panic!() }).collect();
    workers.sort();
    workers.dedup();
    assert_eq!(workers.len(), 2, "two frames at a time on two workers, never more: {workers:?}");
    assert_ne!(workers, [i64::from(std::process::id())], "cooked in a worker process");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_plugin_node_is_cached_and_an_edited_plugin_recooks_only_what_it_feeds() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("offset.py"), OFFSET).unwrap();
    let ctx = CookCtx::new();
    let cook = |registry: &Registry, ev: &mut Evaluator| -> Vec<String> {
        let g = graph(registry, FLAME_OFFSET);
        let v = ev.output(&g, "off.image", &ctx).unwrap();
        let _ = frames(v, &ctx);
        let _ = ev.output(&g, "flame.clip", &ctx).unwrap();
        ev.take_log()
    };
    let mut ev = Evaluator::new();
    let first = cook(&registry_with(dir.path(), 1), &mut ev);
    assert!(first.iter().any(|l| l.contains("off")) && first.iter().any(|l| l.contains("flame")), "{first:?}");
    let again = cook(&registry_with(dir.path(), 1), &mut ev);
    assert!(again.is_empty(), "the same plugin file: nothing re-cooks: {again:?}");
    std::fs::write(dir.path().join("offset.py"), OFFSET.replace("np.float32(amount)", "np.float32(amount * 2)")).unwrap();
    let edited = cook(&registry_with(dir.path(), 1), &mut ev);
    assert!(edited.iter().any(|l| l.contains("off")), "the edited node re-cooks: {edited:?}");
    assert!(!edited.iter().any(|l| l.contains("flame")), "what feeds it does not: {edited:?}");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn broken_plugins_are_errors_naming_their_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("offset.py", OFFSET);
    write(
        "raises.py",
        "from pyrograph_plugin import node, Image\n\n@node(\"studio.raises\")\ndef raises(image: Image) -> Image:\n    \"\"\"Fails.\"\"\"\n    return 1 // 0\n",
    );
    write(
        "wrong.py",
        "import numpy as np\nfrom pyrograph_plugin import node, Image\n\n@node(\"studio.wrong\")\ndef wrong(image: Image) -> Image:\n    \"\"\"Returns float64.\"\"\"\n    return image.astype(np.float64)\n",
    );
    write("syntax.py", "from pyrograph_plugin import node\n\ndef broken(:\n    pass\n");
    write(
        "clash.py",
        "from pyrograph_plugin import node, Image\n\n@node(\"studio.offset\")\ndef again(image: Image) -> Image:\n    \"\"\"Same name.\"\"\"\n    return image\n\n@node(\"imaging.crop\")\ndef crop(image: Image) -> Image:\n    \"\"\"A built-in's name.\"\"\"\n    return image\n",
    );
    let registry = registry_with(dir.path(), 1);
    let found = registry.extension().unwrap();
    let problems = found.problems.join("\n");
    let path = |f: &str| dir.path().join(f).display().to_string();
    assert!(problems.contains(&format!("plugin {} could not be loaded: SyntaxError", path("syntax.py"))), "{problems}");
    assert!(problems.contains(&format!("{}:3", path("syntax.py"))), "the syntax error's line: {problems}");
    assert!(
        problems.contains(&format!("'studio.offset' is declared twice: at {}:4 and at {}:", path("clash.py"), path("offset.py"))),
        "{problems}"
    );
    assert!(problems.contains(&format!("{}:9: 'imaging.crop' is a built-in node type", path("clash.py"))), "{problems}");
    assert!(!found.nodes.contains_key("studio.offset"), "a clashing name is used by neither file");
    let flame = |ty: &str| {
        format!(
            r#"(version: 1, nodes: {{
        "flame": (type: "imaging.turbulence_flame", params: {{"width": 16, "height": 16, "frames": 4}}),
        "p": (type: "{ty}"),
    }}, edges: [("flame.clip", "p.image")])"#
        )
    };
    let ctx = CookCtx::new();
    let fails = |ty: &str| -> String {
        let g = graph(&registry, &flame(ty));
        let Value::Clip(clip) = Evaluator::new().output(&g, "p.image", &ctx).unwrap() else { panic!() };
        clip.get(2, &ctx).unwrap_err().to_string()
    };
    let e = fails("studio.raises");
    assert!(e.contains("ZeroDivisionError") && e.contains(&format!("{}:6 in raises", path("raises.py"))), "{e}");
    let e = fails("studio.wrong");
    assert!(e.contains("output 'image'") && e.contains("float64"), "{e}");
    let unknown = GraphDoc::from_ron(&flame("studio.offset")).unwrap();
    let e = Graph::build(&unknown, &registry, Path::new("."), &BuildOptions::default()).err().unwrap().to_string();
    assert!(e.contains("unknown node type 'studio.offset'") && e.contains("declared twice"), "{e}");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_hanging_plugin_is_killed_when_the_cook_is_cancelled() {
    let dir = tempfile::tempdir().unwrap();
    let pid_file = dir.path().join("pid");
    let plugin = format!(
        "import os\nfrom pyrograph_plugin import node, Image\n\n@node(\"studio.hang\")\ndef hang(image: Image) -> Image:\n    \"\"\"Never returns.\"\"\"\n    open({:?}, \"w\").write(str(os.getpid()))\n    while True:\n        pass\n",
        pid_file.display().to_string()
    );
    std::fs::write(dir.path().join("hang.py"), plugin).unwrap();
    let registry = registry_with(dir.path(), 1);
    let g = graph(
        &registry,
        r#"(version: 1, nodes: {
            "flame": (type: "imaging.turbulence_flame", params: {"width": 16, "height": 16, "frames": 1}),
            "h": (type: "studio.hang"),
        }, edges: [("flame.clip", "h.image")])"#,
    );
    let ctx = CookCtx::new();
    let token = ctx.cancel_token().clone();
    let cook = std::thread::spawn(move || {
        let Value::Clip(clip) = Evaluator::new().output(&g, "h.image", &ctx).unwrap() else { panic!() };
        clip.get(0, &ctx).map(|_| ())
    });
    let started = std::time::Instant::now();
    while !pid_file.is_file() || std::fs::read_to_string(&pid_file).unwrap().is_empty() {
        assert!(started.elapsed().as_secs() < 60, "the plugin never started");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let pid: i32 = std::fs::read_to_string(&pid_file).unwrap().parse().unwrap();
    let cancelled = std::time::Instant::now();
    token.cancel();
    let result = cook.join().unwrap();
    assert!(result.as_ref().is_err_and(|e| e.is_cancelled()), "{result:?}");
    let waited = cancelled.elapsed();
    assert!(waited.as_millis() < 1000, "the cook returned {waited:?} after the cancel");
    // The worker is gone: /proc has no entry for a killed and reaped process.
    assert!(!Path::new(&format!("/proc/{pid}")).exists(), "worker {pid} still runs");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn ramps_and_curves_reach_python_as_their_keys() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("ramps.py"),
        "from pyrograph_plugin import node, ColorRamp, Curve, Float\n\n@node(\"studio.ramps\")\ndef ramps(ramp: ColorRamp = [(0.0, 0, 0, 0, 1), (1.0, 1, 0.8, 0.3, 1)], falloff: Curve = [(0.0, 0.0), (1.0, 1.0)]) -> Float:\n    \"\"\"Sums what it got.\"\"\"\n    return float(ramp.sum() + 10 * falloff.shape[0] + 100 * ramp.shape[1])\n",
    )
    .unwrap();
    let registry = registry_with(dir.path(), 1);
    let ctx = CookCtx::new();
    let value = |ron: &str| match Evaluator::new().output(&graph(&registry, ron), "r.value", &ctx).unwrap() {
        Value::Float(x) => x,
        other => panic!("{other:?}"),
    };
    let defaults = value(r#"(version: 1, nodes: {"r": (type: "studio.ramps")}, edges: [])"#);
    assert!((defaults - (5.1 + 20.0 + 500.0)).abs() < 1e-9, "{defaults}");
    let set = value(
        r#"(version: 1, nodes: {"r": (type: "studio.ramps", params: {"falloff": [(0.0, 1.0), (0.5, 2.0), (1.0, 3.0)]})}, edges: [])"#,
    );
    assert!((set - (5.1 + 30.0 + 500.0)).abs() < 1e-9, "a curve set in the graph file: {set}");
}

#[test]
#[ignore = "needs python3 with numpy: .ci/run installs it and runs the ignored tests"]
fn a_plugin_file_that_hangs_while_loading_is_given_up_on_and_named() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a_hangs.py"), "while True:\n    pass\n").unwrap();
    std::fs::write(dir.path().join("offset.py"), OFFSET).unwrap();
    let mut registry = pyrograph_frontend::registry();
    let mut options = PluginOptions::new(vec![PluginDir { path: dir.path().to_path_buf(), origin: "--plugins" }]);
    options.python = pyrograph_testing::python_with_numpy();
    options.describe_timeout = std::time::Duration::from_secs(2);
    extend(&mut registry, &options).unwrap();
    let started = std::time::Instant::now();
    let found = registry.extension().unwrap();
    let problems = found.problems.join("\n");
    assert!(problems.contains("a_hangs.py could not be loaded: the Python worker did not answer within 2.0 s"), "{problems}");
    assert!(found.nodes.contains_key("studio.offset"), "the next file is read by a fresh worker");
    assert!(started.elapsed().as_secs() < 30, "{:?}", started.elapsed());
    assert!(registry.extension_is_stale(), "asking again may help: a front end makes a new registry");
}
