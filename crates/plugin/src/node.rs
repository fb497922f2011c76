//! A node type declared in Python: described like a built-in, cooked by sending its inputs to a
//! worker (numbers as JSON, pixels through the arena) and reading its outputs back checked. A
//! whole-clip node's worker asks for the frames of its clip inputs one at a time while it runs and
//! hands its output frames over one at a time, so neither side holds a whole clip it does not need.

use std::collections::BTreeMap;
use std::sync::Arc;

use pyrograph_core::value::PortType;
use pyrograph_core::{Channels, Clip, CookCtx, Image, Inputs, Node, NodeDesc, NodeError, TimeDep, Value};
use serde_json::{Map, Value as Json, json};

use crate::arena::{Arena, aligned};
use crate::convert::{param_json, put_image, put_mask, read_image, read_output};
use crate::discover::PluginFile;
use crate::pool::Pool;
use crate::protocol::{ArraySpec, OutputSpec, Reply};
use crate::worker::{Worker, WorkerError};

/// The most frames a whole-clip plugin may make for one clip output: a timeline's longest clip.
pub const MAX_CLIP_FRAMES: usize = 100_000;

/// A plugin node type.
pub struct PyNode {
    /// Its description, from the declaration.
    pub desc: NodeDesc,
    /// The file that declares it.
    pub file: Arc<PluginFile>,
    /// For each input, the channels an image must have (`gray`, `rgba`), if the plugin says.
    pub channels: Vec<Option<String>>,
    /// The workers that cook it.
    pub pool: Arc<Pool>,
    /// The file's and the host's hashes with the type name: a changed plugin re-cooks.
    pub salt: u64,
}

impl Node for PyNode {
    fn desc(&self) -> &NodeDesc {
        &self.desc
    }

    fn fingerprint_salt(&self) -> u64 {
        self.salt
    }

    fn cook(&self, inputs: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let whole_clip = self.desc.time == TimeDep::WholeClip;
        let outcome = self.pool.with_worker(Some(ctx), whole_clip, |worker| Ok(self.cook_on(worker, inputs.values(), ctx)));
        outcome.unwrap_or_else(|e| Err(self.worker_error(e)))
    }
}

/// What one cook keeps while its worker runs: the clips it may ask frames of, where frames and
/// outputs go in the arena, the frames emitted so far, and the first upstream failure.
struct Session {
    clips: BTreeMap<String, Clip>,
    /// The rate of the first clip input, in declared order: the rate of the clips it makes.
    fps: Option<f64>,
    out_offset: u64,
    emitted: BTreeMap<String, Vec<Value>>,
    upstream: Option<NodeError>,
}

impl PyNode {
    fn worker_error(&self, e: WorkerError) -> NodeError {
        match e {
            WorkerError::Cancelled => NodeError::Cancelled,
            WorkerError::Broken(why) => NodeError::Message(format!("{why} (plugin {})", self.file.path.display())),
        }
    }

    /// One cook on one worker: inputs in, the request, the worker's questions answered, outputs back.
    fn cook_on(&self, worker: &mut Worker, values: &[Value], ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let (request, mut session) = self.request(&worker.arena, values)?;
        worker.send(&request).map_err(|e| self.worker_error(e))?;
        loop {
            // A worker that keeps talking (a generator yielding fast) must not outrun a cancel.
            if ctx.cancel_token().is_cancelled() {
                worker.discard();
                return Err(NodeError::Cancelled);
            }
            let reply = worker.receive(Some(ctx)).map_err(|e| self.worker_error(e))?;
            let answer = match reply {
                Reply::NeedFrame { id, clip, index } => session.frame(&worker.arena, id, &clip, index, ctx),
                Reply::Emit { id, port, array, .. } => match session.emit(&worker.arena, &port, &array) {
                    Ok(()) => json!({"op": "ack", "id": id}),
                    Err(e) => {
                        // The worker waits for an answer it will not get: it cannot be used again.
                        worker.discard();
                        return Err(NodeError::Message(format!("output '{port}': {e}")));
                    }
                },
                Reply::Result { outputs, .. } => return self.read_outputs(&worker.arena, &outputs, session),
                Reply::Error(failure) => {
                    return Err(match failure.kind.as_str() {
                        "cancelled" => NodeError::Cancelled,
                        "frame_error" => session.upstream.take().unwrap_or(NodeError::Message(failure.error.message)),
                        "port" => NodeError::Message(failure.error.message),
                        _ => NodeError::Message(failure.error.render()),
                    });
                }
                other => {
                    worker.discard();
                    return Err(NodeError::Message(format!("the Python worker answered a cook with '{}'", other.op())));
                }
            };
            worker.send(&answer).map_err(|e| self.worker_error(e))?;
        }
    }

    /// The cook request, with images and masks written to the arena and clips kept for later.
    fn request(&self, arena: &Arena, values: &[Value]) -> Result<(Json, Session), NodeError> {
        let (mut params, mut arrays, mut clip_info) = (Map::new(), Map::new(), Map::new());
        let mut clips = BTreeMap::new();
        let mut fps = None;
        let mut offset = 0u64;
        for ((port, value), channels) in self.desc.inputs.iter().zip(values).zip(&self.channels) {
            let at_port = |e: String| NodeError::port(&port.name, e);
            pyrograph_core::declare::check_range(port, value).map_err(at_port)?;
            let spec = match value {
                Value::Image(img) => {
                    check_channels(img, channels.as_deref()).map_err(at_port)?;
                    put_image(arena, offset, img)
                }
                Value::Mask(mask) => put_mask(arena, offset, mask),
                Value::Clip(clip) => {
                    clip_info.insert(port.name.clone(), json!({"len": clip.len(), "fps": clip.fps()}));
                    clips.insert(port.name.clone(), clip.clone());
                    fps = fps.or(Some(clip.fps()));
                    continue;
                }
                other => {
                    params.insert(port.name.clone(), param_json(other).map_err(at_port)?);
                    continue;
                }
            };
            let spec = spec.map_err(|e| NodeError::port(&port.name, format!("could not pass the pixels to Python: {e}")))?;
            offset = aligned(spec.offset + byte_len(&spec));
            arrays.insert(port.name.clone(), json!(spec));
        }
        let request = json!({
            "op": "cook", "id": 1, "type": self.desc.type_name, "file": self.file.path, "sha256": self.file.sha256,
            "frame": Json::Null, "params": params, "arrays": arrays, "clips": clip_info, "out_offset": offset,
        });
        Ok((request, Session { clips, fps, out_offset: offset, emitted: BTreeMap::new(), upstream: None }))
    }

    /// The outputs in declared order, each checked against its declared type; a clip output is
    /// the frames emitted for it, at the first clip input's rate.
    fn read_outputs(&self, arena: &Arena, outputs: &[OutputSpec], mut session: Session) -> Result<Vec<Value>, NodeError> {
        let fps = session.fps.unwrap_or(24.0);
        self.desc
            .outputs
            .iter()
            .map(|port| {
                let fail = |e: String| NodeError::Message(format!("output '{}': {e}", port.name));
                let out = outputs
                    .iter()
                    .find(|o| o.port == port.name)
                    .ok_or_else(|| fail("the plugin returned nothing for it".into()))?;
                if port.ty.clip_element().is_none() {
                    return read_output(arena, &port.ty, out).map_err(fail);
                }
                let frames = session.emitted.remove(&port.name).unwrap_or_default();
                if frames.is_empty() || out.frames != Some(frames.len() as u64) {
                    let said = out.frames.map_or("no count".to_string(), |n| n.to_string());
                    return Err(fail(format!("{} frames arrived, and the plugin said {said}", frames.len())));
                }
                Ok(Value::Clip(Clip::from_frames(PortType::Image, fps, frames)))
            })
            .collect()
    }
}

impl Session {
    /// The answer to a worker asking for frame `index` of clip input `clip`: the frame written at
    /// the output offset (the worker copies it before it asks again or writes an output), or why
    /// it failed (kept, so the cook reports the upstream node's own error).
    fn frame(&mut self, arena: &Arena, id: u64, clip: &str, index: i64, ctx: &CookCtx) -> Json {
        let image =
            self.clips.get(clip).ok_or_else(|| NodeError::Message(format!("there is no clip input '{clip}'"))).and_then(|c| {
                let i = usize::try_from(index).ok().filter(|&i| i < c.len());
                let i =
                    i.ok_or_else(|| NodeError::Message(format!("frame {index} is outside the clip of {} frames", c.len())))?;
                match c.get(i, ctx)? {
                    Value::Image(img) => Ok(img),
                    other => Err(NodeError::Message(format!("frame {i} of '{clip}' is a {}, not an image", other.type_name()))),
                }
            });
        let written = image.and_then(|img| {
            put_image(arena, self.out_offset, &img)
                .map_err(|e| NodeError::Message(format!("could not pass a frame to Python: {e}")))
        });
        match written {
            Ok(spec) => json!({"op": "frame", "id": id, "array": spec}),
            Err(e) => {
                let message = e.to_string();
                self.upstream.get_or_insert(e);
                json!({"op": "frame_error", "id": id, "message": message})
            }
        }
    }

    /// Copies out a frame the worker emitted for clip output `port`.
    fn emit(&mut self, arena: &Arena, port: &str, array: &ArraySpec) -> Result<(), String> {
        let frames = self.emitted.entry(port.to_string()).or_default();
        if frames.len() >= MAX_CLIP_FRAMES {
            return Err(format!("the plugin made more than {MAX_CLIP_FRAMES} frames (a generator that never ends?)"));
        }
        let frame = read_image(arena, array).map_err(|e| format!("frame {}: {e}", frames.len()))?;
        frames.push(Value::Image(Arc::new(frame)));
        Ok(())
    }
}

fn byte_len(spec: &ArraySpec) -> u64 {
    let item = if spec.dtype == "|u1" { 1 } else { 4 };
    spec.shape.iter().product::<u64>() * item
}

fn check_channels(img: &Image, wanted: Option<&str>) -> Result<(), String> {
    match (wanted, img.channels()) {
        (Some("gray"), Channels::Rgba) => Err("the plugin takes gray images; convert with imaging.to_gray first".into()),
        (Some("rgba"), Channels::Gray) => Err("the plugin takes RGBA images; this one is gray".into()),
        _ => Ok(()),
    }
}
