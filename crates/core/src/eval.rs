//! The lazy, memoizing evaluator: cooks the upstream cone of the requested nodes in topological
//! order, independent branches in parallel, and re-uses every result whose fingerprint is unchanged.
//!
//! A node's fingerprint hashes its type, whether it is lifted, and the *content* fingerprints of
//! its inputs. So a changed parameter re-cooks that node and its downstream only, and when a
//! re-cooked output equals the old one, its consumers see the same input fingerprint and stay
//! cached (salsa's "backdating"). A file a node reads (a `PathRole::Input` port) is part of its
//! fingerprint as it is on disk (size and modification time, or a folder's entries), so rewriting
//! the file re-cooks its readers. Every actual cook is appended to a recompute log for tests.

use std::collections::{HashMap, HashSet, VecDeque};
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use petgraph::stable_graph::NodeIndex;
use rayon::prelude::*;

use crate::ctx::{CookCtx, Progress};
use crate::error::NodeError;
use crate::fingerprint::{Fingerprinter, hash_path_on_disk};
use crate::graph::{Graph, GraphNode, InputSource};
use crate::node::{Inputs, Node, PathRole, TimeDep};
use crate::value::frame_cache::FrameCache;
use crate::value::{Clip, FrameSource, PortType, Value};

#[derive(Clone)]
struct CacheEntry {
    fingerprint: u64,
    outputs: Arc<[Value]>,
    out_fps: Arc<[u64]>,
}

/// The outcome of one node in a cook.
pub type NodeResult = Result<Arc<[Value]>, NodeError>;

/// Results of the nodes cooked so far in one cook, with their output fingerprints.
type Done = HashMap<NodeIndex, (NodeResult, Option<Arc<[u64]>>)>;

/// Results of a cook, per node of the cooked cone.
#[derive(Default)]
pub struct CookResult {
    results: HashMap<Arc<str>, NodeResult>,
}

impl CookResult {
    /// The outcome of node `id`, if it was in the cooked cone.
    pub fn node(&self, id: &str) -> Option<&NodeResult> {
        self.results.get(id)
    }

    /// Output `port` of node `id` (errors say why it is not there).
    pub fn output(&self, graph: &Graph, id: &str, port: &str) -> Result<Value, NodeError> {
        let res = self.results.get(id).ok_or_else(|| NodeError::msg(format!("node '{id}' was not cooked")))?;
        let values = res.as_ref().map_err(|e| self.cause(e))?;
        let desc = graph.desc(id).ok_or_else(|| NodeError::msg(format!("no node '{id}'")))?;
        let p = desc.output_index(port).ok_or_else(|| NodeError::port(port, format!("node '{id}' has no output '{port}'")))?;
        values.get(p).cloned().ok_or_else(|| NodeError::port(port, format!("node '{id}' produced no output '{port}'")))
    }

    /// Gives each include whose outputs were cooked a result of its own under its id, read
    /// from the inner nodes its outputs stand for (an "upstream failed" echo of the first inner
    /// node that failed).
    fn add_includes(&mut self, graph: &Graph) {
        let mut found = Vec::new();
        for id in graph.include_ids() {
            let Some(inc) = graph.included(id) else { continue };
            let mut values = Vec::with_capacity(inc.outputs.len());
            let mut outcome: Option<NodeResult> = None;
            for (idx, port) in &inc.outputs {
                match self.results.get(&*graph.node(*idx).id) {
                    Some(Ok(vals)) => values.push(vals[*port].clone()),
                    // An echo, like any node downstream of a failure: the inner node reports it.
                    Some(Err(_)) => {
                        outcome = Some(Err(NodeError::Upstream(graph.node(*idx).id.to_string())));
                        break;
                    }
                    None => {
                        outcome = None;
                        values.clear();
                        break;
                    }
                }
            }
            let outcome = match outcome {
                Some(failed) => Some(failed),
                None if values.len() == inc.outputs.len() => Some(Ok(values.into())),
                None => None,
            };
            if let Some(o) = outcome {
                found.push((id.clone(), o));
            }
        }
        self.results.extend(found);
    }

    /// The error behind `e`: an "upstream failed" echo is followed up the chain of failed nodes to
    /// the one that failed on its own, so a caller asking for a downstream output learns why
    /// (the error names that node and its port), not only that something upstream broke.
    fn cause(&self, e: &NodeError) -> NodeError {
        let mut cur = e;
        // A DAG's chain of echoes is at most as long as the list of results.
        for _ in 0..=self.results.len() {
            let NodeError::Upstream(up) = cur else { break };
            match self.results.get(up.as_str()) {
                Some(Err(next)) => cur = next,
                _ => break,
            }
        }
        cur.clone()
    }

    /// Every failed node with its error, in no particular order.
    pub fn errors(&self) -> impl Iterator<Item = (&str, &NodeError)> {
        self.results.iter().filter_map(|(k, v)| v.as_ref().err().map(|e| (&**k, e)))
    }

    /// Whether every node of the cone cooked.
    pub fn is_ok(&self) -> bool {
        self.results.values().all(Result::is_ok)
    }

    /// The errors that are a node's own (not "upstream failed" echoes), for reporting.
    pub fn root_errors(&self) -> Vec<(&str, &NodeError)> {
        let mut v: Vec<_> = self.errors().filter(|(_, e)| !matches!(e, NodeError::Upstream(_))).collect();
        v.sort_by(|a, b| a.0.cmp(b.0));
        v
    }
}

/// Cooks graphs, keeping results between cooks.
#[derive(Default)]
pub struct Evaluator {
    cache: HashMap<Arc<str>, CacheEntry>,
    log: Vec<Arc<str>>,
}

struct Outcome {
    result: NodeResult,
    entry: Option<CacheEntry>,
    cooked: bool,
}

impl Evaluator {
    /// An evaluator with an empty cache.
    pub fn new() -> Self {
        Evaluator::default()
    }

    /// Node ids actually cooked (not served from the cache), in cook order, since the last take.
    pub fn take_log(&mut self) -> Vec<String> {
        std::mem::take(&mut self.log).iter().map(|s| s.to_string()).collect()
    }

    /// Forgets every cached result.
    pub fn clear(&mut self) {
        self.cache.clear();
    }

    /// Cooks `targets` and their upstream cone. Unknown ids are an error; node failures are in
    /// the result, per node, and do not stop unrelated branches.
    pub fn cook(&mut self, graph: &Graph, targets: &[&str], ctx: &CookCtx) -> Result<CookResult, NodeError> {
        let mut roots = Vec::with_capacity(targets.len());
        for t in targets {
            roots.extend(graph.roots(t).ok_or_else(|| NodeError::msg(format!("no node '{t}' in the graph")))?);
        }
        let levels = levels_of_cone(graph, &roots);
        let mut results: Done = HashMap::new();
        for level in levels {
            let outcomes: Vec<(NodeIndex, Outcome)> = if level.len() == 1 {
                vec![(level[0], self.cook_node(graph, level[0], &results, ctx))]
            } else {
                level.par_iter().map(|&i| (i, self.cook_node(graph, i, &results, ctx))).collect()
            };
            for (idx, outcome) in outcomes {
                let id = graph.node(idx).id.clone();
                if outcome.cooked {
                    self.log.push(id.clone());
                }
                let fps = outcome.entry.as_ref().map(|e| e.out_fps.clone());
                if let Some(entry) = outcome.entry
                    && graph.node(idx).node.desc().time != TimeDep::Sink
                {
                    self.cache.insert(id, entry);
                }
                results.insert(idx, (outcome.result, fps));
            }
        }
        let live: HashSet<&str> = graph.topo_order().iter().map(|i| &*graph.node(*i).id).collect();
        self.cache.retain(|k, _| live.contains(&**k));
        // The cook has let go of the frames it was using: bring the shared cache back to budget.
        FrameCache::global().trim();
        let results: HashMap<Arc<str>, NodeResult> =
            results.into_iter().map(|(idx, (r, _))| (graph.node(idx).id.clone(), r)).collect();
        let mut result = CookResult { results };
        result.add_includes(graph);
        Ok(result)
    }

    /// Cooks one output port (`"node.port"`) and returns its value.
    pub fn output(&mut self, graph: &Graph, endpoint: &str, ctx: &CookCtx) -> Result<Value, NodeError> {
        let (id, port) = crate::document::split_endpoint(endpoint)
            .ok_or_else(|| NodeError::msg(format!("'{endpoint}' is not of the form node.port")))?;
        self.cook(graph, &[id], ctx)?.output(graph, id, port)
    }

    fn cook_node(&self, graph: &Graph, idx: NodeIndex, done: &Done, ctx: &CookCtx) -> Outcome {
        let gn = graph.node(idx);
        let fail = |e| Outcome { result: Err(e), entry: None, cooked: false };
        let (values, fingerprint) = match gather_inputs(graph, gn, done) {
            Ok(v) => v,
            Err(e) => return fail(e),
        };
        let desc = gn.node.desc();
        if desc.time != TimeDep::Sink
            && let Some(hit) = self.cache.get(&gn.id).filter(|c| c.fingerprint == fingerprint)
        {
            return Outcome { result: Ok(hit.outputs.clone()), entry: Some(hit.clone()), cooked: false };
        }
        if let Err(e) = ctx.check_cancel() {
            return fail(e);
        }
        let node_ctx = ctx.for_node(&gn.id);
        node_ctx.report(Progress::NodeStarted { node: gn.id.clone() });
        let cooked = if gn.lifted {
            Ok(lift(gn, values, fingerprint))
        } else {
            guarded(|| gn.node.cook(&Inputs::new(desc, &values), &node_ctx))
                .and_then(|out| check_outputs(gn, out))
                .map(|out| out.into_iter().map(|v| name_clip(gn, v)).collect())
        };
        node_ctx.report(Progress::NodeFinished { node: gn.id.clone(), ok: cooked.is_ok() });
        match cooked {
            Ok(outputs) => {
                let out_fps: Arc<[u64]> = outputs.iter().map(Value::fingerprint).collect();
                let outputs: Arc<[Value]> = outputs.into();
                let entry = CacheEntry { fingerprint, outputs: outputs.clone(), out_fps };
                Outcome { result: Ok(outputs), entry: Some(entry), cooked: true }
            }
            Err(e) => Outcome { result: Err(wrap(gn, e)), entry: None, cooked: true },
        }
    }
}

/// Runs a node's cook, turning a panic (a bug: a node met an input it did not expect) into an
/// error of that node, so one node's bug fails its own branch with a message instead of taking
/// the process (a farm task, a Python interpreter, the editor) down with it.
fn guarded(cook: impl FnOnce() -> Result<Vec<Value>, NodeError>) -> Result<Vec<Value>, NodeError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(cook)).unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        Err(NodeError::msg(format!("internal error, a bug in pyrograph (please report it with the graph): {what}")))
    })
}

fn wrap(gn: &GraphNode, e: NodeError) -> NodeError {
    match e {
        NodeError::Upstream(_) | NodeError::InNode { .. } => e,
        other => {
            NodeError::InNode { node: gn.id.to_string(), type_name: gn.node.desc().type_name.clone(), source: Box::new(other) }
        }
    }
}

/// A clip a node made names that node in its frames' errors (a simulation's frame computed when
/// a writer downstream pulls it).
fn name_clip(gn: &GraphNode, v: Value) -> Value {
    match v {
        Value::Clip(c) => Value::Clip(c.named(&gn.id, &gn.node.desc().type_name)),
        v => v,
    }
}

fn check_outputs(gn: &GraphNode, out: Vec<Value>) -> Result<Vec<Value>, NodeError> {
    let want = &gn.node.desc().outputs;
    if out.len() != want.len() {
        return Err(NodeError::msg(format!("produced {} outputs, its description declares {}", out.len(), want.len())));
    }
    Ok(out)
}

/// Input values and the node's fingerprint; `Err` when an upstream node failed.
fn gather_inputs(graph: &Graph, gn: &GraphNode, done: &Done) -> Result<(Vec<Value>, u64), NodeError> {
    let mut h = Fingerprinter::new();
    gn.node.desc().type_name.hash(&mut h);
    gn.lifted.hash(&mut h);
    gn.node.fingerprint_salt().hash(&mut h);
    let mut values = Vec::with_capacity(gn.inputs.len());
    for (src, port) in gn.inputs.iter().zip(&gn.node.desc().inputs) {
        match src {
            InputSource::Const(v) => {
                v.hash_into(&mut h);
                values.push(v.clone());
            }
            InputSource::Edge { from, port: out } => match done.get(from) {
                Some((Ok(vals), fps)) => {
                    let fp = fps.as_ref().map_or_else(|| vals[*out].fingerprint(), |f| f[*out]);
                    h.write_u64(fp);
                    values.push(vals[*out].clone());
                }
                _ => return Err(NodeError::Upstream(graph.node(*from).id.to_string())),
            },
            InputSource::Missing => return Err(NodeError::port(&port.name, "required input is not connected")),
            InputSource::Invalid => {
                return Err(NodeError::port(&port.name, "parameter value was rejected when the graph loaded"));
            }
        }
        if let (Some(PathRole::Input), Some(Value::Path(path))) = (port.path_role, values.last()) {
            hash_path_on_disk(&mut h, path);
        }
    }
    Ok((values, h.finish()))
}

/// Groups the upstream cone of `roots` into levels whose nodes depend only on earlier levels.
fn levels_of_cone(graph: &Graph, roots: &[NodeIndex]) -> Vec<Vec<NodeIndex>> {
    let mut cone: HashSet<NodeIndex> = HashSet::new();
    let mut queue: VecDeque<NodeIndex> = roots.iter().copied().collect();
    while let Some(i) = queue.pop_front() {
        if cone.insert(i) {
            queue.extend(graph.upstream(i));
        }
    }
    let mut level: HashMap<NodeIndex, usize> = HashMap::new();
    let mut levels: Vec<Vec<NodeIndex>> = Vec::new();
    for &i in graph.topo_order().iter().filter(|i| cone.contains(i)) {
        let l = graph.upstream(i).filter_map(|u| level.get(&u)).map(|l| l + 1).max().unwrap_or(0);
        level.insert(i, l);
        if levels.len() <= l {
            levels.resize_with(l + 1, Vec::new);
        }
        levels[l].push(i);
    }
    levels
}

/// A per-frame node run over clips: one lazy clip per output; frame i cooks the node on frame i
/// of every clip input (constants stay constant), with its animated parameters sampled at frame i.
/// The clip is as long as the shortest input clip.
struct Lifted {
    node: Arc<dyn Node>,
    id: Arc<str>,
    inputs: Vec<Value>,
    lift: Vec<bool>,
    len: usize,
    fps: f64,
    /// Hash of the node type, its salt and the clip rate.
    base: u64,
    /// The sum of [`input_key`] over the inputs that are the same at every frame: summed, not
    /// hashed in order, so a parameter keyed to the constant it had keeps every frame's key.
    constants: u64,
    recent: Mutex<VecDeque<(usize, Arc<Vec<Value>>)>>,
    /// Frame keys computed so far (a chain of lifted nodes asks for them repeatedly).
    keys: Mutex<HashMap<usize, Option<u64>>>,
}

/// How many recent frames a multi-output lifted node keeps, so sibling output clips share work.
const LIFTED_RECENT: usize = 16;

impl Lifted {
    /// The inputs of frame `frame`: clip inputs' frames and animated parameters sampled there.
    fn frame_inputs(&self, frame: usize, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let desc = self.node.desc();
        let mut values = Vec::with_capacity(self.inputs.len());
        for ((v, lift), port) in self.inputs.iter().zip(&self.lift).zip(&desc.inputs) {
            match (v, lift) {
                (Value::Clip(c), true) => values.push(c.get(frame, ctx)?),
                (Value::Anim(a), _) => {
                    values.push(a.sample_in(frame as f64, self.fps, port.range).map_err(|e| NodeError::port(&port.name, e))?)
                }
                _ => values.push(v.clone()),
            }
        }
        Ok(values)
    }

    /// What frame `frame`'s outputs depend on, without computing them: the base, the clip
    /// inputs' frame keys and the animated parameters' values there. `None` when a sample fails
    /// (cooking the frame reports why).
    fn frame_key(&self, frame: usize) -> Option<u64> {
        if let Some(k) = self.keys.lock().ok().and_then(|m| m.get(&frame).copied()) {
            return k;
        }
        let mut sum = self.constants;
        let mut ok = true;
        for (i, ((v, lift), port)) in self.inputs.iter().zip(&self.lift).zip(&self.node.desc().inputs).enumerate() {
            match (v, lift) {
                (Value::Clip(c), true) => sum = sum.wrapping_add(input_key(i, c.frame_key(frame))),
                (Value::Anim(a), _) => match a.sample_in(frame as f64, self.fps, port.range) {
                    Ok(sampled) => sum = sum.wrapping_add(input_key(i, sampled.fingerprint())),
                    Err(_) => ok = false,
                },
                _ => {}
            }
        }
        let key = ok.then(|| {
            let mut h = Fingerprinter::new();
            (self.base, sum).hash(&mut h);
            h.finish()
        });
        if let Ok(mut m) = self.keys.lock() {
            m.insert(frame, key);
        }
        key
    }

    fn frame_outputs(&self, frame: usize, ctx: &CookCtx) -> Result<Arc<Vec<Value>>, NodeError> {
        if let Some(hit) = self.recent.lock().ok().and_then(|r| r.iter().find(|(f, _)| *f == frame).map(|(_, v)| v.clone())) {
            return Ok(hit);
        }
        let desc = self.node.desc();
        let in_frame = |e: NodeError| NodeError::InNode {
            node: self.id.to_string(),
            type_name: desc.type_name.clone(),
            source: Box::new(NodeError::Frame { frame, source: Box::new(e) }),
        };
        let values = self.frame_inputs(frame, ctx).map_err(|e| match e {
            NodeError::Port { .. } => in_frame(e),
            other => other,
        })?;
        let node_ctx = ctx.for_node(&self.id);
        node_ctx.log_frame(frame);
        let out = guarded(|| self.node.cook(&Inputs::new(desc, &values), &node_ctx)).map_err(in_frame)?;
        if out.len() != desc.outputs.len() {
            return Err(in_frame(NodeError::msg("wrong number of outputs")));
        }
        let out = Arc::new(out);
        if desc.outputs.len() > 1
            && let Ok(mut r) = self.recent.lock()
        {
            r.push_back((frame, out.clone()));
            if r.len() > LIFTED_RECENT {
                r.pop_front();
            }
        }
        Ok(out)
    }
}

/// Input `index`'s share of a frame key, from the fingerprint of its value at that frame.
fn input_key(index: usize, value: u64) -> u64 {
    let mut h = Fingerprinter::new();
    (index, value).hash(&mut h);
    h.finish()
}

struct LiftedPort {
    lifted: Arc<Lifted>,
    port: usize,
}

impl FrameSource for LiftedPort {
    fn len(&self) -> usize {
        self.lifted.len
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(self.lifted.frame_outputs(index, ctx)?[self.port].clone())
    }
    fn frame_key(&self, index: usize) -> Option<u64> {
        let mut h = Fingerprinter::new();
        h.write_u64(self.lifted.frame_key(index)?);
        h.write_usize(self.port);
        Some(h.finish())
    }
}

fn lift(gn: &GraphNode, inputs: Vec<Value>, fingerprint: u64) -> Vec<Value> {
    let desc = gn.node.desc();
    let lift: Vec<bool> =
        inputs.iter().zip(&desc.inputs).map(|(v, p)| matches!(v, Value::Clip(_)) && !matches!(p.ty, PortType::Clip(_))).collect();
    let clips =
        || inputs.iter().zip(&lift).filter(|(_, l)| **l).filter_map(|(v, _)| if let Value::Clip(c) = v { Some(c) } else { None });
    let len = clips().map(Clip::len).min().unwrap_or(0);
    let fps = clips().next().map_or(24.0, Clip::fps);
    let mut constants = 0u64;
    for (i, ((v, l), port)) in inputs.iter().zip(&lift).zip(&desc.inputs).enumerate() {
        if !*l && !matches!(v, Value::Anim(_)) {
            let mut h = Fingerprinter::new();
            v.hash_into(&mut h);
            // As in the node's fingerprint: a file it reads counts as it is on disk.
            if let (Some(PathRole::Input), Value::Path(path)) = (port.path_role, v) {
                hash_path_on_disk(&mut h, path);
            }
            constants = constants.wrapping_add(input_key(i, h.finish()));
        }
    }
    let mut h = Fingerprinter::new();
    desc.type_name.hash(&mut h);
    gn.node.fingerprint_salt().hash(&mut h);
    // The rate is part of every frame's key: an expression of `time` samples differently at another fps.
    fps.to_bits().hash(&mut h);
    let base = h.finish();
    let lifted = Arc::new(Lifted {
        node: gn.node.clone(),
        id: gn.id.clone(),
        inputs,
        lift,
        len,
        fps,
        base,
        constants,
        recent: Mutex::new(VecDeque::new()),
        keys: Mutex::new(HashMap::new()),
    });
    desc.outputs
        .iter()
        .enumerate()
        .map(|(port, p)| {
            let mut h = Fingerprinter::new();
            (fingerprint, port).hash(&mut h);
            let source = Arc::new(LiftedPort { lifted: lifted.clone(), port });
            Value::Clip(Clip::new(p.ty.clone(), fps, h.finish(), source))
        })
        .collect()
}
