//! Clips: lazy, random-access sequences of per-frame values, computed on demand and cached in
//! the shared frame cache.

use std::fmt;
use std::hash::Hasher;
use std::sync::Arc;

use rayon::prelude::*;

use crate::ctx::CookCtx;
use crate::error::NodeError;
use crate::fingerprint::Fingerprinter;
use crate::value::frame_cache::{ClipKey, FrameCache, next_clip_id};
use crate::value::{Image, PortType, Value};

/// Produces the frames of a [`Clip`] on demand.
pub trait FrameSource: Send + Sync {
    /// Number of frames.
    fn len(&self) -> usize;
    /// Whether the clip has no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Computes frame `index` (`index < len()`); results are cached by the clip.
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError>;
    /// A key for frame `index`'s content that is known without computing it (a per-frame node's
    /// frame: its inputs' frame keys and its parameters sampled at that frame). A clip whose
    /// source gives one caches the frame under it, so a re-cooked node serves every frame whose
    /// key did not change from the cache: moving one key re-cooks only the frames it moved.
    fn frame_key(&self, _index: usize) -> Option<u64> {
        None
    }
}

/// The frame-cache index under which content-keyed frames are kept: no clip has that many frames,
/// so a content key never meets a clip id's frames.
const KEYED: usize = usize::MAX;

/// A lazy, random-access sequence of per-frame values; each frame is computed on demand and cached.
#[derive(Clone)]
pub struct Clip {
    element: PortType,
    fps: f64,
    fingerprint: u64,
    source: Arc<dyn FrameSource>,
    key: Arc<ClipKey>,
}

impl fmt::Debug for Clip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Clip<{}>({} frames @ {} fps)", self.element, self.len(), self.fps)
    }
}

/// A clip whose frames are already in memory.
struct VecSource(Vec<Value>);

impl FrameSource for VecSource {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(self.0[index].clone())
    }
}

/// A clip's source whose frames' errors name the node that made the clip.
struct Named {
    inner: Arc<dyn FrameSource>,
    node: String,
    type_name: String,
}

impl FrameSource for Named {
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        self.inner.frame(index, ctx).map_err(|e| match e {
            e @ (NodeError::InNode { .. } | NodeError::Cancelled | NodeError::Upstream(_)) => e,
            e @ NodeError::Frame { .. } => {
                NodeError::InNode { node: self.node.clone(), type_name: self.type_name.clone(), source: Box::new(e) }
            }
            e => NodeError::InNode {
                node: self.node.clone(),
                type_name: self.type_name.clone(),
                source: Box::new(NodeError::Frame { frame: index, source: Box::new(e) }),
            },
        })
    }
    fn frame_key(&self, index: usize) -> Option<u64> {
        self.inner.frame_key(index)
    }
}

impl Clip {
    /// A lazy clip. `fingerprint` must change whenever the frames could.
    pub fn new(element: PortType, fps: f64, fingerprint: u64, source: Arc<dyn FrameSource>) -> Self {
        Clip::with_cache(element, fps, fingerprint, source, FrameCache::global())
    }

    /// A lazy clip whose frames are cached in `cache` instead of the process-wide one.
    pub fn with_cache(
        element: PortType,
        fps: f64,
        fingerprint: u64,
        source: Arc<dyn FrameSource>,
        cache: Arc<FrameCache>,
    ) -> Self {
        let key = Arc::new(ClipKey { id: next_clip_id(), cache });
        Clip { element, fps, fingerprint, source, key }
    }

    /// A clip of frames already computed; its fingerprint is the hash of their content.
    pub fn from_frames(element: PortType, fps: f64, frames: Vec<Value>) -> Self {
        let mut h = Fingerprinter::new();
        frames.iter().for_each(|f| h.write_u64(f.fingerprint()));
        Clip::new(element, fps, h.finish(), Arc::new(VecSource(frames)))
    }

    /// The same clip (same frames, fingerprint and cache entries) whose frames' errors name
    /// `node` of type `type_name`, the node that made it: a simulation's frame that fails while
    /// a writer downstream pulls it is that simulation's error, not the writer's. Errors already
    /// naming a node (an upstream clip's) pass unchanged.
    pub fn named(self, node: &str, type_name: &str) -> Clip {
        let source = Arc::new(Named { inner: self.source, node: node.to_string(), type_name: type_name.to_string() });
        Clip { source, ..self }
    }

    /// The per-frame type.
    pub fn element(&self) -> &PortType {
        &self.element
    }

    /// Frames per second (metadata for writers and players).
    pub fn fps(&self) -> f64 {
        self.fps
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.source.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Identity of the clip's content.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// What identifies frame `index`'s content: its source's frame key, else the clip's
    /// fingerprint and the index.
    pub fn frame_key(&self, index: usize) -> u64 {
        self.source.frame_key(index).unwrap_or_else(|| {
            let mut h = Fingerprinter::new();
            h.write_u64(self.fingerprint);
            h.write_usize(index);
            h.finish()
        })
    }

    /// Frame `index`, computed on first use and cached.
    pub fn get(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        if index >= self.len() {
            return Err(NodeError::msg(format!("frame {index} is past the end of a {}-frame clip", self.len())));
        }
        let (id, slot) = match self.source.frame_key(index) {
            Some(k) => (k, KEYED),
            None => (self.key.id, index),
        };
        if let Some(v) = self.key.cache.get(id, slot) {
            return Ok(v);
        }
        ctx.check_cancel()?;
        let v = self.source.frame(index, ctx).map_err(|e| match e {
            NodeError::Message(_) | NodeError::Port { .. } => NodeError::Frame { frame: index, source: Box::new(e) },
            other => other,
        })?;
        self.key.cache.put(id, slot, &v);
        Ok(v)
    }

    /// Frame `index` as an image (the clip must be a `Clip<Image>`).
    pub fn image(&self, index: usize, ctx: &CookCtx) -> Result<Arc<Image>, NodeError> {
        match self.get(index, ctx)? {
            Value::Image(img) => Ok(img),
            other => Err(NodeError::msg(format!("frame {index}: expected an Image, got {}", other.type_name()))),
        }
    }

    /// All frames in `range`, computed in parallel; reports per-frame progress through `ctx`.
    pub fn materialize_range(&self, range: std::ops::Range<usize>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        let total = range.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        range
            .into_par_iter()
            .map(|i| {
                let v = self.get(i, ctx)?;
                let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                ctx.frame_progress(n, total);
                Ok(v)
            })
            .collect()
    }

    /// Every frame, in parallel.
    pub fn materialize(&self, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        self.materialize_range(0..self.len(), ctx)
    }
}
