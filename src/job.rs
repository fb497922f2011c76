//! `pyrograph job`: an Open Job Description job bundle that renders a graph on a farm.
//!
//! The bundle is what AWS Deadline Cloud submits unchanged and what `openjd run` runs locally:
//! `template.yaml` (jobtemplate-2023-09, one `Render` step whose tasks are chunks of the
//! frames), `parameter_values.yaml` (Deadline's `parameterValues` list) and `job_params.yaml`
//! (the same values as a map, for `openjd run -p file://job_params.yaml`). Every task runs
//! `pyrograph render GRAPH --out OUT --frames <its chunk> --skip-existing`, so a re-queued task
//! redoes only the frames it had not finished, and leaves a manifest of its files in
//! `OUT/.pyrograph-job/` for `pyrograph job collect`. The graph is referenced where it lies (a farm
//! shares storage), so its includes and relative inputs resolve as they do here.
//!
//! A graph with volume simulations gets a `Simulate` step first: one task steps every simulation
//! once (`pyrograph simulate`) into a VDB cache under `OUT/.pyrograph-job/sim`, and the render
//! tasks, which depend on it, read that cache (`--sim-cache`) instead of each simulating up to its
//! chunk.
//!
//! The YAML is written by hand: it is a fixed shape whose every scalar is emitted as a JSON
//! string (YAML reads JSON strings as strings), which a YAML library would not make safer.

use std::path::{Path, PathBuf};

use std::sync::Arc;

use pyrograph_core::{FrameSet, Graph};

/// The type of the nodes a job's Simulate step steps.
pub const SIMULATION_TYPE: &str = "volume.simulate";

/// The simulation nodes of a graph (includes flattened), by id.
pub fn simulations(graph: &Graph) -> Vec<Arc<str>> {
    let mut ids: Vec<Arc<str>> = graph
        .topo_order()
        .iter()
        .map(|i| graph.node(*i))
        .filter(|n| n.node.desc().type_name == SIMULATION_TYPE)
        .map(|n| n.id.clone())
        .collect();
    ids.sort();
    ids
}

/// What a job renders and how its frames are cut into tasks.
#[derive(Clone, Debug)]
pub struct JobSpec {
    /// Job name shown by the farm.
    pub name: String,
    /// The pyrograph binary the workers run (absolute).
    pub pyrograph: PathBuf,
    /// The graph file (absolute).
    pub graph: PathBuf,
    /// The output folder (absolute).
    pub out: PathBuf,
    /// Frames to render.
    pub frames: FrameSet,
    /// Frames per task.
    pub chunk: usize,
    /// `--set node.param=value` overrides, passed to every task.
    pub sets: Vec<String>,
    /// `--wedge` arguments, passed to every task.
    pub wedge: Vec<String>,
    /// `--wedge-zip` arguments, passed to every task.
    pub wedge_zip: Vec<String>,
    /// Number of wedge variants (0 without a wedge): a `Wedge` task parameter multiplies the
    /// frame chunks, and each task renders one variant (`--wedge-index`).
    pub variants: usize,
    /// Use the TASK_CHUNKING extension (`CHUNK[INT]`); without it the chunks are listed as a
    /// STRING task parameter, for schedulers that lack the extension.
    pub task_chunking: bool,
    /// The limits the job was written under (`--read-root DIR`, `--max-nodes N`, …), passed to
    /// every task so that a farm renders under the same confinement as the check.
    pub limits: Vec<String>,
    /// The graph has volume simulations: a `Simulate` step (one task per wedge variant) steps
    /// them once into a VDB cache, and the `Render` step depends on it and reads the cache.
    pub simulate: bool,
}

/// The simulation cache's folder under the output folder, in template syntax.
const SIM_CACHE: &str = "{{Param.Out}}/.pyrograph-job/sim";

/// The files of a job bundle, by name.
pub struct Bundle {
    /// `(file name, contents)`.
    pub files: Vec<(&'static str, String)>,
}

fn q(s: &str) -> String {
    serde_json::Value::String(s.to_string()).to_string()
}

fn path_text(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

impl JobSpec {
    /// The bundle's files.
    pub fn bundle(&self) -> Bundle {
        Bundle {
            files: vec![
                ("template.yaml", self.template()),
                ("parameter_values.yaml", self.parameter_values()),
                ("job_params.yaml", self.job_params()),
                ("pyrograph_job.json", self.job_json()),
            ],
        }
    }

    fn params(&self) -> [(&'static str, String); 4] {
        [
            ("Pyrograph", path_text(&self.pyrograph)),
            ("Graph", path_text(&self.graph)),
            ("Out", path_text(&self.out)),
            ("Frames", self.frames.to_string()),
        ]
    }

    /// The job template (jobtemplate-2023-09).
    pub fn template(&self) -> String {
        let mut t = String::from("specificationVersion: 'jobtemplate-2023-09'\n");
        if self.task_chunking {
            t += "extensions:\n- TASK_CHUNKING\n";
        }
        t += &format!("name: {}\n", q(&self.name));
        t += "parameterDefinitions:\n";
        for (name, kind, extra) in [
            ("Pyrograph", "PATH", "  objectType: FILE\n  dataFlow: IN\n"),
            ("Graph", "PATH", "  objectType: FILE\n  dataFlow: IN\n"),
            ("Out", "PATH", "  objectType: DIRECTORY\n  dataFlow: OUT\n"),
        ] {
            t += &format!("- name: {name}\n  type: {kind}\n{extra}");
        }
        t += &format!("- name: Frames\n  type: STRING\n  default: {}\n", q(&self.frames.to_string()));
        t += "steps:\n";
        if self.simulate {
            t += &self.simulate_step();
        }
        t += "- name: Render\n";
        if self.simulate {
            t += "  dependencies:\n  - dependsOn: Simulate\n";
        }
        t += "  parameterSpace:\n    taskParameterDefinitions:\n";
        if self.task_chunking {
            let contiguous = matches!(self.frames.ranges(), [r] if r.step == 1);
            t += &format!(
                "    - name: Frame\n      type: CHUNK[INT]\n      range: \"{{{{Param.Frames}}}}\"\n      chunks:\n        \
                 defaultTaskCount: {}\n        rangeConstraint: {}\n",
                self.chunk.max(1),
                if contiguous { "CONTIGUOUS" } else { "NONCONTIGUOUS" }
            );
        } else {
            let chunks: Vec<String> = self.frames.chunks(self.chunk).iter().map(|c| q(&c.to_string())).collect();
            t += &format!("    - name: Frame\n      type: STRING\n      range: [{}]\n", chunks.join(", "));
        }
        if self.variants > 0 {
            t += &format!("    - name: Wedge\n      type: INT\n      range: \"0-{}\"\n", self.variants - 1);
            t += "    combination: \"Wedge * Frame\"\n";
        }
        let manifest = if self.variants > 0 {
            format!(
                "{{{{Param.Out}}}}/{}/task-w{{{{Task.Param.Wedge}}}}-{{{{Task.Param.Frame}}}}.json",
                crate::manifest::TASK_DIR
            )
        } else {
            format!("{{{{Param.Out}}}}/{}/task-{{{{Task.Param.Frame}}}}.json", crate::manifest::TASK_DIR)
        };
        let mut args = vec![
            q("render"),
            q("{{Param.Graph}}"),
            q("--out"),
            q("{{Param.Out}}"),
            q("--frames"),
            q("{{Task.Param.Frame}}"),
            q("--skip-existing"),
            q("--manifest"),
            q(&manifest),
        ];
        if self.simulate {
            args.extend([q("--sim-cache"), q(&self.sim_cache())]);
        }
        self.push_variant_args(&mut args);
        t += "  script:\n    actions:\n      onRun:\n        command: \"{{Param.Pyrograph}}\"\n";
        t += &format!("        args: [{}]\n", args.join(", "));
        t
    }

    /// The cache folder of a task (one per wedge variant).
    fn sim_cache(&self) -> String {
        if self.variants > 0 { format!("{SIM_CACHE}/w{{{{Task.Param.Wedge}}}}") } else { SIM_CACHE.to_string() }
    }

    /// `--set`, the wedge and the limits: what every task of both steps is given.
    fn push_variant_args(&self, args: &mut Vec<String>) {
        for (flag, values) in [("--set", &self.sets), ("--wedge", &self.wedge), ("--wedge-zip", &self.wedge_zip)] {
            for v in values {
                args.push(q(flag));
                args.push(q(v));
            }
        }
        if self.variants > 0 {
            args.push(q("--wedge-index"));
            args.push(q("{{Task.Param.Wedge}}"));
        }
        args.extend(self.limits.iter().map(|a| q(a)));
    }

    /// The step that simulates once per variant, before any chunk renders. A re-queued task
    /// whose cache is whole leaves it (`--skip-existing`); one that stopped part-way steps
    /// again from the first frame (`--overwrite`), as a simulation has no state but its past.
    fn simulate_step(&self) -> String {
        let mut t = String::from("- name: Simulate\n");
        if self.variants > 0 {
            t += "  parameterSpace:\n    taskParameterDefinitions:\n";
            t += &format!("    - name: Wedge\n      type: INT\n      range: \"0-{}\"\n", self.variants - 1);
        }
        let mut args = vec![
            q("simulate"),
            q("{{Param.Graph}}"),
            q("--sim-cache"),
            q(&self.sim_cache()),
            q("--out"),
            q("{{Param.Out}}"),
            q("--frames"),
            q("{{Param.Frames}}"),
            q("--skip-existing"),
            q("--overwrite"),
        ];
        self.push_variant_args(&mut args);
        t += "  script:\n    actions:\n      onRun:\n        command: \"{{Param.Pyrograph}}\"\n";
        t += &format!("        args: [{}]\n", args.join(", "));
        t
    }

    /// Deadline Cloud's job-bundle parameter file.
    pub fn parameter_values(&self) -> String {
        let mut t = String::from("parameterValues:\n");
        for (name, value) in self.params() {
            t += &format!("- name: {name}\n  value: {}\n", q(&value));
        }
        t
    }

    /// What `job collect` checks the tasks against.
    pub fn job_json(&self) -> String {
        let v = serde_json::json!({
            "graph": path_text(&self.graph),
            "out": path_text(&self.out),
            "frames": self.frames.to_string(),
            "variants": self.variants,
        });
        format!("{v:#}\n")
    }

    /// The same values as a map, for `openjd run -p file://job_params.yaml`.
    pub fn job_params(&self) -> String {
        self.params().iter().map(|(name, value)| format!("{name}: {}\n", q(value))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(frames: &str, chunking: bool) -> JobSpec {
        JobSpec {
            name: "cube \"test\"".into(),
            pyrograph: "/bin/pyrograph".into(),
            graph: "/g/burning-cube.ron".into(),
            out: "/o".into(),
            frames: frames.parse().unwrap(),
            chunk: 8,
            sets: vec!["spread.fps=12".into()],
            wedge: Vec::new(),
            wedge_zip: Vec::new(),
            variants: 0,
            task_chunking: chunking,
            limits: vec!["--read-root".into(), "/studio/footage".into()],
            simulate: false,
        }
    }

    #[test]
    fn a_chunked_template_names_its_extension_and_chunk_size() {
        let t = spec("0-47", true).template();
        assert!(t.contains("extensions:\n- TASK_CHUNKING\n"), "{t}");
        assert!(t.contains("type: CHUNK[INT]") && t.contains("defaultTaskCount: 8") && t.contains("CONTIGUOUS"), "{t}");
        assert!(t.contains(r#"name: "cube \"test\"""#), "names are quoted: {t}");
        assert!(t.contains(r#""--set", "spread.fps=12""#), "{t}");
        assert!(t.contains(r#""--read-root", "/studio/footage""#), "tasks read under the job's confinement: {t}");
        assert!(spec("0-47:2", true).template().contains("NONCONTIGUOUS"));
    }

    #[test]
    fn without_the_extension_the_chunks_are_listed() {
        let t = spec("0-19", false).template();
        assert!(!t.contains("TASK_CHUNKING"), "{t}");
        assert!(t.contains(r#"range: ["0-7", "8-15", "16-19"]"#), "{t}");
    }

    #[test]
    fn a_wedge_multiplies_the_chunks_and_picks_a_variant_per_task() {
        let s = JobSpec { wedge: vec!["wind.seed=1,2,3".into()], variants: 3, ..spec("0-47", true) };
        let t = s.template();
        assert!(
            t.contains("    - name: Wedge\n      type: INT\n      range: \"0-2\"\n    combination: \"Wedge * Frame\"\n"),
            "{t}"
        );
        assert!(t.contains(r#""--wedge", "wind.seed=1,2,3", "--wedge-index", "{{Task.Param.Wedge}}""#), "{t}");
        assert!(t.contains("task-w{{Task.Param.Wedge}}-{{Task.Param.Frame}}.json"), "{t}");
        assert!(s.job_json().contains("\"variants\": 3"));
    }

    #[test]
    fn a_graph_that_simulates_gets_a_simulate_step_that_the_render_step_depends_on() {
        let t = JobSpec { simulate: true, ..spec("0-47", true) }.template();
        let (sim, render) = t.split_once("- name: Render\n").expect("a Render step");
        assert!(sim.contains("- name: Simulate\n") && !sim.contains("parameterSpace"), "one task: {t}");
        assert!(
            sim.contains(r#"args: ["simulate", "{{Param.Graph}}", "--sim-cache", "{{Param.Out}}/.pyrograph-job/sim""#),
            "{t}"
        );
        assert!(
            sim.contains(r#""--frames", "{{Param.Frames}}", "--skip-existing", "--overwrite", "--set", "spread.fps=12""#),
            "{t}"
        );
        assert!(render.starts_with("  dependencies:\n  - dependsOn: Simulate\n  parameterSpace:"), "{t}");
        assert!(render.contains(r#""--sim-cache", "{{Param.Out}}/.pyrograph-job/sim""#), "{t}");
        let w = JobSpec { simulate: true, wedge: vec!["s.seed=1,2".into()], variants: 2, ..spec("0-47", true) }.template();
        let (sim, render) = w.split_once("- name: Render\n").unwrap();
        assert!(sim.contains("    - name: Wedge\n      type: INT\n      range: \"0-1\"\n"), "a variant per task: {w}");
        for step in [sim, render] {
            assert!(step.contains(r#""--sim-cache", "{{Param.Out}}/.pyrograph-job/sim/w{{Task.Param.Wedge}}""#), "{w}");
            assert!(step.contains(r#""--wedge-index", "{{Task.Param.Wedge}}""#), "{w}");
        }
        assert!(!spec("0-47", true).template().contains("Simulate"), "no step for a graph without simulations");
    }

    #[test]
    fn parameter_files_carry_the_same_values() {
        let s = spec("0-47", true);
        assert!(s.parameter_values().contains("- name: Graph\n  value: \"/g/burning-cube.ron\"\n"));
        assert!(s.job_params().contains("Frames: \"0-47\"\n"));
    }
}
