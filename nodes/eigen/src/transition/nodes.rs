//! The node types of recognition and the motion transitions: `eigen.recognize`,
//! `eigen.lowpass_transition`, `eigen.direct_bridging` and `eigen.end_growing`.

use std::ops::RangeInclusive;
use std::sync::Arc;

use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, NodeError, port};

use super::distance::row;
use super::{
    Kernel, ThetaMin, check_range, clip_thresholds, direct_bridging, end_exclusion, end_growing_adaptive, exclusion_mask,
    lowpass_transition, parse_thresholds, recognize,
};
use crate::pca::components_to_use;
use crate::values::{Basis, FrameItem, FrameList, Weights};

fn frames_value(frames: impl IntoIterator<Item = usize>) -> Arc<FrameList> {
    Arc::new(FrameList { items: frames.into_iter().map(|f| FrameItem::Frame(f as u32)).collect() })
}

pyrograph_core::ports! {
    /// The database and the two motions a transition joins: the first ports of every transition node.
    pub struct MotionPair {
        /// The database's training weights.
        weights: Arc<Weights>,
        /// First database frame of motion T1.
        #[range(0, 100_000_000)]
        t1_start: usize = 0,
        /// Last database frame of T1 (α, inclusive).
        #[range(0, 100_000_000)]
        t1_end: usize = 49,
        /// First database frame of motion T2 (β).
        #[range(0, 100_000_000)]
        t2_start: usize = 100,
        /// Last database frame of T2 (inclusive).
        #[range(0, 100_000_000)]
        t2_end: usize = 149,
    }
}

impl MotionPair {
    /// T1 and T2, checked against the database; errors name the end port of the bad range.
    fn ranges(&self) -> Result<(RangeInclusive<usize>, RangeInclusive<usize>), NodeError> {
        let t1 = self.t1_start..=self.t1_end;
        let t2 = self.t2_start..=self.t2_end;
        check_range(&t1, self.weights.frames, "T1").map_err(|m| NodeError::port(port!(MotionPair, t1_end), m))?;
        check_range(&t2, self.weights.frames, "T2").map_err(|m| NodeError::port(port!(MotionPair, t2_end), m))?;
        Ok((t1, t2))
    }
}

// ---------------------------------------------------------------------------------------------
// eigen.recognize
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Finds the database frame most similar to each query: minimum D_ab = ‖Ω_a − Ω_b‖ (thesis §4.5, eq. 21).
    ///
    /// Frames closer than theta_min are rejected (near-copies cause slow motion); the nearest of the rest wins.
    /// The query is each row of query, or database frame `frame` when frame ≥ 0 (that frame and `exclude`
    /// frames either side of it are skipped).
    #[node("eigen.recognize", "Eigenfires", WholeClip)]
    pub struct Recognize {
        /// The database's training weights.
        weights: Arc<Weights>,
        /// Weights to recognize (e.g. eigen.project of new frames); unused when frame ≥ 0.
        query: Arc<Weights> = Arc::new(Weights::default()),
        /// Query this database frame instead; -1 = use query.
        #[range(-1, 100_000_000)]
        frame: i64 = -1,
        /// With frame: also skip this many frames either side of it.
        #[range(0, 100_000)]
        exclude: usize = 0,
        /// E for detection; 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Minimum distance θ_min; nearer frames are rejected.
        #[range(0.0, 1e9)]
        theta_min: f64 = 0.0,
    }
    pub struct RecognizeOut {
        /// The recognized database frame per query.
        frames: Arc<FrameList>,
        /// Distance of the first query's match.
        distance: f64,
    }
}

impl Cook for Recognize {
    fn cook(self, _: &CookCtx) -> Result<RecognizeOut, NodeError> {
        let db = &*self.weights;
        let e =
            components_to_use(self.components, db.components).map_err(|m| NodeError::port(port!(Recognize, components), m))?;
        let theta_min = self.theta_min;
        let mut excluded = vec![false; db.frames];
        // A negative frame (-1) means: use the query.
        let queries: Vec<Vec<f32>> = if let Ok(f) = usize::try_from(self.frame) {
            if f >= db.frames {
                return Err(NodeError::port(
                    port!(Recognize, frame),
                    format!("frame {f} is past the database's {} frames", db.frames),
                ));
            }
            let near = self.exclude;
            excluded[f.saturating_sub(near)..=(f + near).min(db.frames - 1)].iter_mut().for_each(|x| *x = true);
            vec![row(db, f).to_vec()]
        } else {
            let q = &*self.query;
            if q.frames == 0 {
                return Err(NodeError::port(port!(Recognize, query), "no query: connect weights to query or set frame"));
            }
            if q.components < e {
                return Err(NodeError::port(
                    port!(Recognize, query),
                    format!("has {} components, detection uses {e}", q.components),
                ));
            }
            (0..q.frames).map(|r| row(q, r).to_vec()).collect()
        };
        let mut found = Vec::with_capacity(queries.len());
        let mut first = 0.0;
        for (qi, q) in queries.iter().enumerate() {
            let (f, d) = recognize(db, q, e, theta_min, &excluded).ok_or_else(|| {
                NodeError::port(
                    port!(Recognize, theta_min),
                    format!("no database frame is at least theta_min = {theta_min} from query {qi} (and not excluded); lower it"),
                )
            })?;
            if qi == 0 {
                first = d;
            }
            found.push(f);
        }
        Ok(RecognizeOut { frames: frames_value(found), distance: first })
    }
}

// ---------------------------------------------------------------------------------------------
// eigen.lowpass_transition
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Morphs from motion T1 to T2 by low-pass filtering their weights along time (thesis §5.1.1, Fig. 34).
    ///
    /// The weight vectors of T1 + T2 are filtered with the kernel over the first `components` eigenfires (50 in
    /// the thesis); the filtered vectors at the last `span` frames of T1 and the first `span` of T2 are the
    /// output and replace those frames (box3, span 2: four morphed frames). end_weighted is K = [1/5, 1/5, 3/5],
    /// mirrored on the T2 side. detail copies each weight past `components` from the original frame with that
    /// probability, to bring back fine detail.
    #[node("eigen.lowpass_transition", "Eigenfires", WholeClip)]
    pub struct LowpassTransition {
        /// The database and the two motions.
        motions: MotionPair,
        /// Eigenfires filtered (low frequencies).
        #[range(1, 1_000_000)]
        components: usize = 50,
        /// Filter kernel.
        kernel: Kernel = Kernel::Box3,
        /// Morphed frames on each side of the seam.
        #[range(1, 10_000)]
        span: usize = 2,
        /// Probability of copying each weight past `components` from the original.
        #[range(0.0, 1.0)]
        detail: f64 = 0.0,
        /// Seed of the detail copy.
        #[range(0, i64::MAX)]
        seed: u64 = 0,
    }
    /// 2·span synthesized weight vectors (the transition).
    -> frames: Arc<FrameList>
}

impl Cook for LowpassTransition {
    fn cook(self, _: &CookCtx) -> Result<Arc<FrameList>, NodeError> {
        let db = &*self.motions.weights;
        let (t1, t2) = self.motions.ranges()?;
        let e = components_to_use(self.components, db.components)
            .map_err(|m| NodeError::port(port!(LowpassTransition, components), m))?;
        let out = lowpass_transition(db, t1, t2, e, &self.kernel.weights(), self.span, self.detail, self.seed)
            .map_err(|m| NodeError::port(port!(LowpassTransition, span), m))?;
        Ok(Arc::new(FrameList { items: out.into_iter().map(FrameItem::Weights).collect() }))
    }
}

// ---------------------------------------------------------------------------------------------
// eigen.direct_bridging
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Connects motion T1 to T2 through real frames near the straight line between them (thesis §5.1.2.1, Fig. 36).
    ///
    /// The line from α (last frame of T1) to β (first frame of T2) is divided into steps + 1 parts; for each of
    /// the `steps` points the nearest database frame is taken, outside T1 and T2, not taken before, and at least
    /// theta_min from the previous frame.
    #[node("eigen.direct_bridging", "Eigenfires", WholeClip)]
    pub struct DirectBridgingTransition {
        /// The database and the two motions.
        motions: MotionPair,
        /// Number of frames N to insert.
        #[range(1, 100_000)]
        steps: usize = 3,
        /// E for detection; 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Minimum distance θ_min between consecutive frames.
        #[range(0.0, 1e9)]
        theta_min: f64 = 0.0,
    }
    /// The inserted database frames.
    -> frames: Arc<FrameList>
}

impl Cook for DirectBridgingTransition {
    fn cook(self, _: &CookCtx) -> Result<Arc<FrameList>, NodeError> {
        let db = &*self.motions.weights;
        let (t1, t2) = self.motions.ranges()?;
        let e = components_to_use(self.components, db.components)
            .map_err(|m| NodeError::port(port!(DirectBridgingTransition, components), m))?;
        let excluded = exclusion_mask(db.frames, &[t1.clone(), t2.clone()]);
        let path = direct_bridging(db, *t1.end(), *t2.start(), self.steps, e, self.theta_min, &excluded)
            .map_err(|m| NodeError::port(port!(DirectBridgingTransition, theta_min), m))?;
        Ok(frames_value(path))
    }
}

// ---------------------------------------------------------------------------------------------
// eigen.end_growing
// ---------------------------------------------------------------------------------------------

pyrograph_core::choice! {
    /// Where End Growing's θ_min comes from (§5.1.2.2).
    pub enum ThetaMode {
        /// theta_min everywhere.
        Fixed = "fixed",
        /// One threshold per source clip, from theta_per_clip.
        PerClip = "per_clip",
        /// Each clip's threshold measured from its succeeding frames.
        Measured = "measured",
    }
}

pyrograph_core::node! {
    /// Connects motion T1 to T2 by growing paths of similar frames from both ends until they meet (thesis §5.1.2.2, Algorithm 1).
    ///
    /// From α (last frame of T1) and β (first frame of T2) each step moves both ends to the nearest frames that
    /// shrink the gap by at least theta_min (Algorithm 1's four distances); frames nearer than theta_min, the last
    /// `exclude` frames of T1, the first `exclude` of T2 and each side's own path are rejected. The paths join at a
    /// shared image or when two of their frames are closer than theta_min; failing that within `steps` it is an
    /// error. optimize drops detours (Optimize_Path).
    ///
    /// theta_mode is the thesis' adaptive θ_min (§5.1.2.2, end): `fixed` uses theta_min everywhere; `per_clip`
    /// gives each source clip (fire A, B, C) its own threshold from theta_per_clip ("2, 2, 6"); `measured` sets
    /// each clip's threshold to theta_scale × the median distance between its succeeding frames. A comparison
    /// uses the mean of the two frames' thresholds. The adaptive modes need the database's basis (frame sources).
    #[node("eigen.end_growing", "Eigenfires", WholeClip)]
    pub struct EndGrowingConnection {
        /// The database and the two motions.
        motions: MotionPair,
        /// Maximum number of frames N (two per step).
        #[range(1, 100_000)]
        steps: usize = 40,
        /// E for detection; 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Minimum threshold θ_min.
        #[range(0.0, 1e9)]
        theta_min: f64 = 0.0,
        /// Frames at the end of T1 and the start of T2 that may not be picked.
        #[range(0, 100_000)]
        exclude: usize = 7,
        /// Drop frames whose removal lowers the larger of their two hops.
        optimize: bool = true,
        /// One θ_min, one per source clip, or measured per clip.
        theta_mode: ThetaMode = ThetaMode::Fixed,
        /// per_clip: θ_min of clip 1, 2, 3 (comma separated).
        theta_per_clip: String = String::new(),
        /// measured: θ_min = scale × median distance of succeeding frames.
        #[range(0.0, 1e6)]
        theta_scale: f64 = 1.0,
        /// The database's basis: where each frame came from (adaptive modes only).
        basis: Arc<Basis> = Arc::new(Basis::default()),
    }
    pub struct EndGrowingConnectionOut {
        /// The inserted database frames.
        frames: Arc<FrameList>,
        /// Steps of Algorithm 1 used.
        steps_taken: usize,
        /// The θ_min used per source clip (comma separated).
        thresholds: String,
    }
}

impl Cook for EndGrowingConnection {
    fn cook(self, _: &CookCtx) -> Result<EndGrowingConnectionOut, NodeError> {
        let db = &*self.motions.weights;
        let (t1, t2) = self.motions.ranges()?;
        let e = components_to_use(self.components, db.components)
            .map_err(|m| NodeError::port(port!(EndGrowingConnection, components), m))?;
        let excluded = end_exclusion(db.frames, &t1, &t2, self.exclude);
        let (theta_min, per_clip) = self.adaptive_theta(db, e)?;
        let r = end_growing_adaptive(db, *t1.end(), *t2.start(), self.steps, e, &theta_min, &excluded, self.optimize)
            .map_err(|m| NodeError::port(port!(EndGrowingConnection, steps), m))?;
        let shown = per_clip.iter().map(|t| format!("{t}")).collect::<Vec<_>>().join(", ");
        Ok(EndGrowingConnectionOut { frames: frames_value(r.path), steps_taken: r.steps, thresholds: shown })
    }
}

impl EndGrowingConnection {
    /// The node's θ_min (fixed, per clip or measured) and the thresholds per clip it stands for.
    fn adaptive_theta(&self, db: &Weights, e: usize) -> Result<(ThetaMin, Vec<f64>), NodeError> {
        let mode = self.theta_mode;
        if mode == ThetaMode::Fixed {
            let t = self.theta_min;
            return Ok((ThetaMin::Fixed(t), vec![t]));
        }
        let basis = &*self.basis;
        if basis.sources.len() != db.frames {
            return Err(NodeError::port(
                port!(EndGrowingConnection, basis),
                format!(
                    "theta_mode {} needs the database's basis (it lists {} source frames, the weights have {} rows)",
                    mode.name(),
                    basis.sources.len(),
                    db.frames
                ),
            ));
        }
        let per_clip = if mode == ThetaMode::PerClip {
            parse_thresholds(&self.theta_per_clip).map_err(|m| NodeError::port(port!(EndGrowingConnection, theta_per_clip), m))?
        } else {
            clip_thresholds(db, &basis.sources, e, self.theta_scale)
                .map_err(|m| NodeError::port(port!(EndGrowingConnection, basis), m))?
        };
        let t = ThetaMin::per_clip(&basis.sources, &per_clip)
            .map_err(|m| NodeError::port(port!(EndGrowingConnection, theta_per_clip), m))?;
        Ok((t, per_clip))
    }
}
