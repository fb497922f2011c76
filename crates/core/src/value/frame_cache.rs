//! One byte budget for every cached clip frame (DESIGN: evaluation and memory).
//!
//! Every [`Clip`](crate::Clip) keeps its computed frames in a [`FrameCache`]; by default all clips
//! of the process share [`FrameCache::global`], so a graph of ten clip stages holds at most one
//! budget of frames, not ten. Eviction is least-recently-used and skips frames a cook still holds
//! (their `Arc` is shared outside the cache): evicting those would free nothing and make the next
//! reader recompute a frame that is in memory anyway. An evicted frame is recomputed by its clip's
//! source on the next request, bit-identically (sources are deterministic). With
//! [`FrameCache::set_compact`], frames of 8-bit content (decoded files and videos) are held at one
//! byte a sample and widened on the way out ([`crate::value::compact`]), so a budget holds four times as
//! many of them.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard};

use lru::LruCache;

use crate::value::Value;
use crate::value::compact::Bytes8;

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

/// A cached frame: as computed, or an 8-bit image in bytes.
enum Entry {
    Value(Value),
    Bytes(Arc<Bytes8>),
}

impl Entry {
    fn new(value: &Value, compact: bool) -> Entry {
        match value {
            Value::Image(img) if compact => {
                Bytes8::pack(img).map_or_else(|| Entry::Value(value.clone()), |b| Entry::Bytes(Arc::new(b)))
            }
            other => Entry::Value(other.clone()),
        }
    }

    fn value(&self) -> Value {
        match self {
            Entry::Value(v) => v.clone(),
            Entry::Bytes(b) => Value::Image(Arc::new(b.unpack())),
        }
    }

    fn byte_size(&self) -> usize {
        match self {
            Entry::Value(v) => v.byte_size(),
            Entry::Bytes(b) => b.byte_size(),
        }
    }

    /// Whether a cook holds this very frame. A packed frame is never shared: each reader gets
    /// its own widened copy, and evicting the bytes frees them.
    fn in_use(&self) -> bool {
        match self {
            Entry::Value(v) => in_use(v),
            Entry::Bytes(_) => false,
        }
    }
}

struct Inner {
    frames: LruCache<Key, Entry>,
    stats: CacheStats,
}

/// A least-recently-used store of clip frames under one byte budget.
pub struct FrameCache {
    inner: Mutex<Inner>,
    /// Whether 8-bit frames are packed into bytes when cached (read on every put, outside the lock).
    compact: AtomicBool,
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
        FrameCache { inner: Mutex::new(Inner { frames: LruCache::unbounded(), stats }), compact: AtomicBool::new(false) }
    }

    /// Holds frames of 8-bit content at one byte a sample (four times as many in a budget), at
    /// the cost of a pass over every frame cached and a widening on every hit. Worth it where
    /// frames are revisited (the editor's previews and scrubber); a render that streams each frame
    /// through once spent a quarter to a third more wall time on it (1080p video to PNGs), so it is
    /// off unless asked for (`render --compact-cache`).
    pub fn set_compact(&self, compact: bool) {
        self.compact.store(compact, Ordering::Relaxed);
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

    /// Evicts down to the budget now. Frames that cooks held when they were cached may keep the
    /// cache over its budget until the next frame is cached; the evaluator trims once a cook is
    /// over and has let go of them.
    pub fn trim(&self) {
        evict(&mut self.lock());
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
        let entry = match inner.frames.get(&(clip, index)) {
            Some(Entry::Value(v)) => Some(Entry::Value(v.clone())),
            Some(Entry::Bytes(b)) => Some(Entry::Bytes(Arc::clone(b))),
            None => None,
        };
        match entry {
            Some(Entry::Value(v)) => {
                inner.stats.hits += 1;
                Some(v)
            }
            Some(bytes) => {
                inner.stats.hits += 1;
                // Widen outside the lock: other threads need not wait for it.
                drop(inner);
                Some(bytes.value())
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
        // Packed before the lock is taken: it reads the whole frame.
        let entry = Entry::new(value, self.compact.load(Ordering::Relaxed));
        let size = entry.byte_size();
        let mut inner = self.lock();
        if size > inner.stats.budget || inner.frames.contains(&(clip, index)) {
            return;
        }
        inner.frames.put((clip, index), entry);
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
            if !v.in_use() {
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
        Value::Custom(v) => super::custom::shared(v),
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
    use crate::ctx::CookCtx;
    use crate::error::NodeError;
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

    /// 8×8 RGBA frames of 8-bit levels, as a decoder makes them (1 KiB as f32, 256 bytes packed).
    struct Decoded(Mutex<Vec<usize>>);

    impl FrameSource for Decoded {
        fn len(&self) -> usize {
            8
        }
        fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
            self.0.lock().unwrap().push(index);
            let data = (0..256).map(|p| ((p * 31 + index * 17) % 256) as f32 / 255.0).collect();
            Ok(Value::Image(Arc::new(Image::from_vec(8, 8, Channels::Rgba, data).unwrap())))
        }
    }

    #[test]
    fn eight_bit_frames_are_held_in_bytes_and_come_back_bit_identical() {
        let source = Arc::new(Decoded(Mutex::new(Vec::new())));
        // Four frames fit at a byte a sample; at four bytes a sample only one would.
        let cache = Arc::new(FrameCache::new(4 * 256));
        cache.set_compact(true);
        let decoded = Clip::with_cache(PortType::Image, 24.0, 3, source.clone(), cache.clone());
        let ctx = CookCtx::new();
        let first: Vec<Vec<u32>> =
            (0..4).map(|i| decoded.image(i, &ctx).unwrap().data().iter().map(|v| v.to_bits()).collect()).collect();
        assert_eq!((cache.stats().frames, cache.stats().bytes), (4, 4 * 256));
        source.0.lock().unwrap().clear();
        for (i, bits) in first.iter().enumerate() {
            let again = decoded.image(i, &ctx).unwrap();
            assert_eq!(again.channels(), Channels::Rgba);
            assert!(again.data().iter().map(|v| v.to_bits()).eq(bits.iter().copied()), "frame {i} bit-identical");
        }
        assert!(source.0.lock().unwrap().is_empty(), "all four answered from the cache");
        // A frame that is not 8-bit content keeps its f32 size.
        let (logged, _, small) = clip(8);
        small.set_compact(true);
        logged.image(0, &ctx).unwrap();
        assert_eq!(small.stats().bytes, 256);
        // Without compaction an 8-bit frame keeps its f32 size too.
        let plain = Arc::new(FrameCache::new(4 * 1024));
        let wide = Clip::with_cache(PortType::Image, 24.0, 4, Arc::new(Decoded(Mutex::new(Vec::new()))), plain.clone());
        wide.image(0, &ctx).unwrap();
        assert_eq!(plain.stats().bytes, 1024);
    }

    /// The frames of `Logged`; cancels `token` the first time frame `at` is computed (a user
    /// pressing Cancel while a writer streams the clip).
    struct CancelAt {
        at: usize,
        token: crate::ctx::CancelToken,
        fired: std::sync::atomic::AtomicBool,
    }

    impl FrameSource for CancelAt {
        fn len(&self) -> usize {
            16
        }
        fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
            if index == self.at && !self.fired.swap(true, Ordering::Relaxed) {
                self.token.cancel();
            }
            Logged(Mutex::new(Vec::new())).frame(index, ctx)
        }
    }

    #[test]
    fn a_cancelled_streaming_cook_leaves_the_cache_consistent() {
        let token = crate::ctx::CancelToken::new();
        let cache = Arc::new(FrameCache::new(4 * 256));
        let source = Arc::new(CancelAt { at: 5, token: token.clone(), fired: Default::default() });
        let streamed = Clip::with_cache(PortType::Image, 24.0, 11, source, cache.clone());
        let ctx = CookCtx::new().with_cancel(token.clone());
        // Pulled in parallel, as a writer does; the cook stops part-way.
        let err = streamed.materialize(&ctx).unwrap_err();
        assert!(err.is_cancelled(), "{err}");
        // The frames in flight were kept though the budget was reached (they were in use); the
        // accounting holds, and once the cook has let go of them, a trim brings it under budget.
        let stats = cache.stats();
        assert!(stats.frames >= 1 && stats.bytes == stats.frames * 256, "{stats:?}");
        cache.trim();
        let stats = cache.stats();
        assert!(stats.bytes == stats.frames * 256 && stats.bytes <= stats.budget, "{stats:?}");
        // The next cook finds what was kept and computes the rest: every frame as a fresh clip's.
        token.reset();
        let (fresh, _, _) = clip(16);
        for i in 0..16 {
            assert_eq!(streamed.image(i, &ctx).unwrap().data(), fresh.image(i, &ctx).unwrap().data(), "frame {i}");
        }
        let stats = cache.stats();
        assert!(stats.bytes == stats.frames * 256 && stats.bytes <= stats.budget, "{stats:?}");
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
