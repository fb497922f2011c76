//! One byte budget for every cached clip frame (DESIGN: evaluation and memory).
//!
//! Every [`Clip`](crate::Clip) keeps its computed frames in a [`FrameCache`]; by default all clips
//! of the process share [`FrameCache::global`], so a graph of ten clip stages holds at most one
//! budget of frames, not ten. Eviction is least-recently-used and skips frames a cook still holds
//! (their `Arc` is shared outside the cache): evicting those would free nothing and make the next
//! reader recompute a frame that is in memory anyway. An evicted frame is recomputed by its clip's
//! source on the next request, bit-identically (sources are deterministic).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard};

use lru::LruCache;

use crate::value::Value;

/// Default budget: enough for eight 1080p RGBA float frames (or 64 gray 8-bit-sized ones), small
/// enough that a streaming cook of any length stays well under a gigabyte. Interactive work can
/// ask for more (`--cache-mb`, the editor's preference).
pub const DEFAULT_BUDGET: usize = 256 << 20;

/// What a cache holds and did, for reports (`render --json`) and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CacheStats {
    /// The budget in bytes.
    pub budget: usize,
    /// Bytes of the frames held now.
    pub bytes: usize,
    /// The most bytes held at once since the last reset.
    pub peak_bytes: usize,
    /// Frames held now.
    pub frames: usize,
    /// Requests answered from the cache.
    pub hits: u64,
    /// Requests that computed the frame.
    pub misses: u64,
    /// Frames evicted to stay within the budget.
    pub evictions: u64,
}

type Key = (u64, usize);

struct Inner {
    frames: LruCache<Key, Value>,
    stats: CacheStats,
}

/// A least-recently-used store of clip frames under one byte budget.
pub struct FrameCache {
    inner: Mutex<Inner>,
}

static GLOBAL: LazyLock<Arc<FrameCache>> = LazyLock::new(|| Arc::new(FrameCache::new(DEFAULT_BUDGET)));
static NEXT_CLIP: AtomicU64 = AtomicU64::new(1);

/// A fresh identity for a clip's frames in a cache (never reused in the process).
pub(crate) fn next_clip_id() -> u64 {
    NEXT_CLIP.fetch_add(1, Ordering::Relaxed)
}

impl FrameCache {
    /// An empty cache holding at most `budget` bytes of frames (frames in use may exceed it).
    pub fn new(budget: usize) -> Self {
        let stats = CacheStats { budget, ..CacheStats::default() };
        FrameCache { inner: Mutex::new(Inner { frames: LruCache::unbounded(), stats }) }
    }

    /// The cache every clip uses unless it was given its own.
    pub fn global() -> Arc<FrameCache> {
        GLOBAL.clone()
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic while holding the lock leaves consistent data (every update is a few field
        // writes after the map changed), so a poisoned lock is still usable.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Sets the budget in bytes and evicts down to it.
    pub fn set_budget(&self, budget: usize) {
        let mut inner = self.lock();
        inner.stats.budget = budget;
        evict(&mut inner);
    }

    /// Counters and sizes.
    pub fn stats(&self) -> CacheStats {
        let inner = self.lock();
        CacheStats { frames: inner.frames.len(), ..inner.stats }
    }

    /// Zeroes the counters and the peak (not the frames held).
    pub fn reset_counters(&self) {
        let mut inner = self.lock();
        inner.stats = CacheStats {
            budget: inner.stats.budget,
            bytes: inner.stats.bytes,
            peak_bytes: inner.stats.bytes,
            ..CacheStats::default()
        };
    }

    /// Frame `index` of clip `clip`, counting a hit or a miss.
    pub(crate) fn get(&self, clip: u64, index: usize) -> Option<Value> {
        let mut inner = self.lock();
        match inner.frames.get(&(clip, index)).cloned() {
            Some(v) => {
                inner.stats.hits += 1;
                Some(v)
            }
            None => {
                inner.stats.misses += 1;
                None
            }
        }
    }

    /// Keeps a computed frame, then evicts the least recently used frames not in use until the
    /// budget holds. A frame larger than the whole budget is not kept.
    pub(crate) fn put(&self, clip: u64, index: usize, value: &Value) {
        let size = value.byte_size();
        let mut inner = self.lock();
        if size > inner.stats.budget || inner.frames.contains(&(clip, index)) {
            return;
        }
        inner.frames.put((clip, index), value.clone());
        inner.stats.bytes += size;
        inner.stats.peak_bytes = inner.stats.peak_bytes.max(inner.stats.bytes);
        evict(&mut inner);
    }

    /// Drops every frame of `clip` (its last handle is gone).
    pub(crate) fn forget(&self, clip: u64) {
        let mut inner = self.lock();
        let keys: Vec<Key> = inner.frames.iter().map(|(k, _)| *k).filter(|k| k.0 == clip).collect();
        for k in keys {
            if let Some(v) = inner.frames.pop(&k) {
                inner.stats.bytes -= v.byte_size();
            }
        }
    }
}

/// Evicts least recently used frames that no cook holds until the budget holds.
fn evict(inner: &mut Inner) {
    if inner.stats.bytes <= inner.stats.budget {
        return;
    }
    // Oldest first; frames shared outside the cache are in use and stay.
    let victims: Vec<Key> = {
        let mut over = inner.stats.bytes - inner.stats.budget;
        let mut out = Vec::new();
        for (k, v) in inner.frames.iter().rev() {
            if over == 0 {
                break;
            }
            if !in_use(v) {
                over = over.saturating_sub(v.byte_size());
                out.push(*k);
            }
        }
        out
    };
    for k in victims {
        if let Some(v) = inner.frames.pop(&k) {
            inner.stats.bytes -= v.byte_size();
            inner.stats.evictions += 1;
        }
    }
}

/// Whether a cached value is also held outside the cache (its `Arc` is shared): a cook is
/// using it.
fn in_use(value: &Value) -> bool {
    fn shared<T: ?Sized>(a: &Arc<T>) -> bool {
        Arc::strong_count(a) > 1
    }
    match value {
        Value::Image(v) => shared(v),
        Value::Mask(v) => shared(v),
        Value::Contours(v) => shared(v),
        Value::WindField(v) => shared(v),
        Value::Particles(v) => shared(v),
        Value::ClothState(v) => shared(v),
        Value::Basis(v) => shared(v),
        Value::Weights(v) => shared(v),
        Value::FrameList(v) => shared(v),
        Value::ParamSeries(v) => shared(v),
        Value::ArModel(v) => shared(v),
        Value::FlameModel(v) => shared(v),
        Value::Mesh(v) => shared(v),
        Value::SpreadState(v) => shared(v),
        // A nested clip keeps its own frames in the cache; a handle to it is small.
        _ => false,
    }
}

/// A clip's identity in its cache; dropping the last handle forgets the clip's frames.
pub(crate) struct ClipKey {
    pub(crate) id: u64,
    pub(crate) cache: Arc<FrameCache>,
}

impl Drop for ClipKey {
    fn drop(&mut self) {
        self.cache.forget(self.id);
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;
    use crate::error::NodeError;
    use crate::eval::CookCtx;
    use crate::value::{Channels, Clip, FrameSource, Image, PortType};

    /// 8×8 gray frames (256 bytes each) whose pixels depend on the index; logs every compute.
    struct Logged(Mutex<Vec<usize>>);

    impl FrameSource for Logged {
        fn len(&self) -> usize {
            16
        }
        fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
            self.0.lock().unwrap().push(index);
            let data = (0..64).map(|p| ((p * 7 + index * 13) % 97) as f32 / 97.0).collect();
            Ok(Value::Image(Arc::new(Image::from_vec(8, 8, Channels::Gray, data).unwrap())))
        }
    }

    fn clip(budget_frames: usize) -> (Clip, Arc<Logged>, Arc<FrameCache>) {
        let source = Arc::new(Logged(Mutex::new(Vec::new())));
        let cache = Arc::new(FrameCache::new(budget_frames * 256));
        (Clip::with_cache(PortType::Image, 24.0, 7, source.clone(), cache.clone()), source, cache)
    }

    fn log(s: &Logged) -> Vec<usize> {
        std::mem::take(&mut *s.0.lock().unwrap())
    }

    #[test]
    fn the_budget_evicts_least_recently_used_and_recomputes_bit_identically() {
        let (clip, src, cache) = clip(3);
        let ctx = CookCtx::new();
        let first: Vec<Vec<f32>> = (0..4).map(|i| clip.image(i, &ctx).unwrap().data().to_vec()).collect();
        assert_eq!(log(&src), [0, 1, 2, 3]);
        assert_eq!(cache.stats().frames, 3, "three frames fit");
        // 0 was least recently used: it went; 1, 2, 3 are answered from the cache.
        for i in 1..4 {
            clip.image(i, &ctx).unwrap();
        }
        assert_eq!(log(&src), Vec::<usize>::new());
        // Frame 1 is touched, so asking for 0 again evicts 2 (now the oldest), not 1.
        clip.image(1, &ctx).unwrap();
        let again = clip.image(0, &ctx).unwrap();
        assert_eq!(log(&src), [0], "only the evicted frame is recomputed");
        assert_eq!(again.data(), &first[0][..], "bit-identical");
        clip.image(1, &ctx).unwrap();
        assert_eq!(log(&src), Vec::<usize>::new(), "1 stayed");
        clip.image(2, &ctx).unwrap();
        assert_eq!(log(&src), [2], "2 was evicted");
        let stats = cache.stats();
        assert!(stats.bytes <= stats.budget && stats.evictions >= 2, "{stats:?}");
        assert_eq!((stats.hits, stats.misses), (5, 6));
    }

    #[test]
    fn a_frame_in_use_is_never_evicted() {
        let (clip, src, cache) = clip(2);
        let ctx = CookCtx::new();
        let held = clip.image(0, &ctx).unwrap();
        for i in 1..8 {
            clip.image(i, &ctx).unwrap();
        }
        log(&src);
        let again = clip.image(0, &ctx).unwrap();
        assert!(Arc::ptr_eq(&held, &again), "frame 0 stayed cached while a cook held it");
        assert_eq!(log(&src), Vec::<usize>::new());
        drop((held, again));
        for i in 1..8 {
            clip.image(i, &ctx).unwrap();
        }
        clip.image(0, &ctx).unwrap();
        assert_eq!(log(&src).last(), Some(&0), "released, it can go");
        assert!(cache.stats().bytes <= 2 * 256);
    }

    #[test]
    fn dropping_the_last_clip_handle_frees_its_frames() {
        let (clip, _src, cache) = clip(8);
        let ctx = CookCtx::new();
        let copy = clip.clone();
        for i in 0..4 {
            copy.image(i, &ctx).unwrap();
        }
        drop(copy);
        assert_eq!(cache.stats().frames, 4, "the clip still has a handle");
        drop(clip);
        assert_eq!((cache.stats().frames, cache.stats().bytes), (0, 0));
    }

    #[test]
    fn a_smaller_budget_evicts_at_once() {
        let (clip, _src, cache) = clip(8);
        let ctx = CookCtx::new();
        for i in 0..8 {
            clip.image(i, &ctx).unwrap();
        }
        cache.set_budget(512);
        assert_eq!(cache.stats().frames, 2);
    }
}
