//! Motion lists and scenarios (thesis §5.1, Figs. 32–33), turning frame lists into clips (§4.8
//! reconstruction, or §7.1.2 "modified video": fetching the source frames), and weight synthesis
//! by hand (§5.2).

use std::ops::RangeInclusive;
use std::sync::Arc;

use pyrograph_core::declare::{ClipOf, Cook};
use pyrograph_core::{Clip, CookCtx, Image, NodeError, PortType, port};
use rayon::prelude::*;

use crate::pca::{components_to_use, empty_clip, reconstruct, samples_to_clip};
use crate::transition::{Kernel, check_range, direct_bridging, end_exclusion, end_growing, exclusion_mask, lowpass_transition};
use crate::values::{Basis, FrameItem, FrameList, Weights};

/// How two motions are joined (§5.1).
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Plain attachment (a visible jump).
    Cut,
    /// §5.1.1 low-pass filter over the first `components`.
    LowPass {
        /// Components filtered.
        components: usize,
        /// Kernel weights (odd length).
        kernel: Vec<f64>,
        /// Morphed frames per side.
        span: usize,
    },
    /// §5.1.2.1 Direct Bridging.
    DirectBridging {
        /// Frames inserted.
        steps: usize,
        /// E for detection.
        components: usize,
        /// θ_min.
        theta_min: f64,
    },
    /// §5.1.2.2 End Growing Connection.
    EndGrowing {
        /// Maximum frames.
        steps: usize,
        /// E for detection.
        components: usize,
        /// θ_min.
        theta_min: f64,
        /// Frames at the end of the first motion and the start of the second that may not be picked.
        exclude: usize,
    },
}

/// The frames joining one motion to the next.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// Frames inserted between the two motions.
    pub items: Vec<FrameItem>,
    /// Frames they replace at the end of the first motion.
    pub trim_end: usize,
    /// Frames they replace at the start of the second motion.
    pub trim_start: usize,
}

/// The transition from motion `x` to motion `y` (database frame ranges) by `method`.
pub fn transition(
    db: &Weights,
    x: &RangeInclusive<usize>,
    y: &RangeInclusive<usize>,
    method: &Method,
) -> Result<Transition, String> {
    let frames = |v: Vec<usize>| v.into_iter().map(|f| FrameItem::Frame(f as u32)).collect();
    Ok(match method {
        Method::Cut => Transition { items: Vec::new(), trim_end: 0, trim_start: 0 },
        Method::LowPass { components, kernel, span } => {
            let out = lowpass_transition(db, x.clone(), y.clone(), *components, kernel, *span, 0.0, 0)?;
            Transition { items: out.into_iter().map(FrameItem::Weights).collect(), trim_end: *span, trim_start: *span }
        }
        Method::DirectBridging { steps, components, theta_min } => {
            let ex = exclusion_mask(db.frames, &[x.clone(), y.clone()]);
            let path = direct_bridging(db, *x.end(), *y.start(), *steps, *components, *theta_min, &ex)?;
            Transition { items: frames(path), trim_end: 0, trim_start: 0 }
        }
        Method::EndGrowing { steps, components, theta_min, exclude } => {
            let ex = end_exclusion(db.frames, x, y, *exclude);
            let r = end_growing(db, *x.end(), *y.start(), *steps, *components, *theta_min, &ex, true)?;
            Transition { items: frames(r.path), trim_end: 0, trim_start: 0 }
        }
    })
}

/// Plays `segments` in order, joined by `method`; with `looped`, a last transition leads from the
/// end of the last segment back into the first (the "producing loop" of §5.1).
pub fn motion_list(
    db: &Weights,
    segments: &[RangeInclusive<usize>],
    looped: bool,
    method: &Method,
) -> Result<Vec<FrameItem>, String> {
    if segments.is_empty() {
        return Err("the scenario has no motions".into());
    }
    for (i, s) in segments.iter().enumerate() {
        check_range(s, db.frames, &format!("motion {}", i + 1))?;
    }
    let k = segments.len();
    let joins = if looped { k } else { k - 1 };
    let trans: Vec<Transition> = (0..joins)
        .map(|i| {
            transition(db, &segments[i], &segments[(i + 1) % k], method)
                .map_err(|m| format!("transition {}→{}: {m}", i + 1, (i + 1) % k + 1))
        })
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for (i, s) in segments.iter().enumerate() {
        let trim_start = if i > 0 {
            trans[i - 1].trim_start
        } else if looped {
            trans[k - 1].trim_start
        } else {
            0
        };
        let trim_end = trans.get(i).map_or(0, |t| t.trim_end);
        let len = s.clone().count();
        if trim_start + trim_end >= len {
            return Err(format!("motion {} ({}-{}) is too short for the transition's span", i + 1, s.start(), s.end()));
        }
        out.extend((s.start() + trim_start..=s.end() - trim_end).map(|f| FrameItem::Frame(f as u32)));
        if let Some(t) = trans.get(i) {
            out.extend(t.items.iter().cloned());
        }
    }
    Ok(out)
}

/// Parses `"T1 = 100-180; T2 = 2000-2050"` into named inclusive ranges.
pub fn parse_motions(text: &str) -> Result<Vec<(String, RangeInclusive<usize>)>, String> {
    let mut out = Vec::new();
    for part in text.split([';', '\n']).map(str::trim).filter(|p| !p.is_empty()) {
        let (name, range) = part.split_once('=').ok_or_else(|| format!("'{part}' is not of the form NAME = A-B"))?;
        let (a, b) = range.trim().split_once('-').ok_or_else(|| format!("'{}' is not a range A-B", range.trim()))?;
        let num = |s: &str| s.trim().parse::<usize>().map_err(|_| format!("'{}' in '{part}' is not a frame number", s.trim()));
        out.push((name.trim().to_string(), num(a)?..=num(b)?));
    }
    if out.is_empty() {
        return Err("no motions defined; write e.g. \"T1 = 100-180; T2 = 400-450\"".into());
    }
    Ok(out)
}

/// Resolves a scenario (`"T1 + T2 + T1"`) against named motions.
pub fn parse_scenario(text: &str, motions: &[(String, RangeInclusive<usize>)]) -> Result<Vec<RangeInclusive<usize>>, String> {
    text.split(['+', ' ', ',', '\n'])
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|name| {
            motions.iter().find(|(n, _)| n == name).map(|(_, r)| r.clone()).ok_or_else(|| {
                let known: Vec<&str> = motions.iter().map(|(n, _)| n.as_str()).collect();
                format!("unknown motion '{name}' (defined: {})", known.join(", "))
            })
        })
        .collect()
}

pyrograph_core::choice! {
    /// The transition method of `eigen.motion_list`: the kinds of [`Method`].
    pub enum MethodKind {
        /// [`Method::Cut`].
        Cut = "cut",
        /// [`Method::LowPass`].
        LowPass = "lowpass",
        /// [`Method::DirectBridging`].
        DirectBridging = "direct_bridging",
        /// [`Method::EndGrowing`].
        EndGrowing = "end_growing",
    }
}

pyrograph_core::node! {
    /// Builds an animation from named motions and a scenario, joined by a motion transition (thesis §5.1, Figs. 32–33).
    ///
    /// motions names ranges of database frames ("T1 = 100-180; T2 = 400-450"); scenario plays them in order
    /// ("T1 + T2 + T1"); loop adds a transition from the last back into the first. method: cut (plain
    /// attachment), lowpass (§5.1.1; its morphed frames replace `span` frames each side of the seam),
    /// direct_bridging (§5.1.2.1; `steps` frames, T1 and T2 frames excluded) or end_growing (§5.1.2.2; at most
    /// `steps` frames).
    #[node("eigen.motion_list", "Eigenfires", WholeClip)]
    pub struct MotionList {
        /// The database's training weights.
        weights: Arc<Weights>,
        /// Named motions: NAME = first-last; …
        motions: String = "T1 = 0-49; T2 = 100-149".to_string(),
        /// Motions in playing order.
        scenario: String = "T1 + T2".to_string(),
        /// Join the end of the last motion back to the first.
        r#loop: bool = false,
        /// Transition method.
        method: MethodKind = MethodKind::EndGrowing,
        /// E for detection (recognition methods); 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Minimum threshold θ_min (recognition methods).
        #[range(0.0, 1e9)]
        theta_min: f64 = 0.0,
        /// Direct Bridging: frames inserted; End Growing: maximum frames.
        #[range(1, 100_000)]
        steps: usize = 40,
        /// End Growing: frames at each motion's end/start that may not be picked.
        #[range(0, 100_000)]
        exclude: usize = 7,
        /// Low-pass: components filtered.
        #[range(1, 1_000_000)]
        lowpass_components: usize = 50,
        /// Low-pass kernel.
        kernel: Kernel = Kernel::Box3,
        /// Low-pass: morphed frames each side of a seam.
        #[range(1, 10_000)]
        span: usize = 2,
    }
    pub struct MotionListOut {
        /// The animation's frames.
        frames: Arc<FrameList>,
        /// Number of frames.
        count: usize,
    }
}

impl Cook for MotionList {
    fn cook(self, _: &CookCtx) -> Result<MotionListOut, NodeError> {
        let db = &*self.weights;
        let motions_port = port!(MotionList, motions);
        let motions = parse_motions(&self.motions).map_err(|m| NodeError::port(motions_port, m))?;
        for (name, r) in &motions {
            check_range(r, db.frames, &format!("motion {name}")).map_err(|m| NodeError::port(motions_port, m))?;
        }
        let segments = parse_scenario(&self.scenario, &motions).map_err(|m| NodeError::port(port!(MotionList, scenario), m))?;
        let components =
            || components_to_use(self.components, db.components).map_err(|m| NodeError::port(port!(MotionList, components), m));
        let method = match self.method {
            MethodKind::Cut => Method::Cut,
            MethodKind::LowPass => Method::LowPass {
                components: components_to_use(self.lowpass_components, db.components)
                    .map_err(|m| NodeError::port(port!(MotionList, lowpass_components), m))?,
                kernel: self.kernel.weights(),
                span: self.span,
            },
            MethodKind::DirectBridging => {
                Method::DirectBridging { steps: self.steps, components: components()?, theta_min: self.theta_min }
            }
            MethodKind::EndGrowing => Method::EndGrowing {
                steps: self.steps,
                components: components()?,
                theta_min: self.theta_min,
                exclude: self.exclude,
            },
        };
        let items =
            motion_list(db, &segments, self.r#loop, &method).map_err(|m| NodeError::port(port!(MotionList, method), m))?;
        let count = items.len();
        Ok(MotionListOut { frames: Arc::new(FrameList { items }), count })
    }
}

/// The weight rows of `items` (database frames are rows of `db`), cut or zero-padded to `e`.
pub fn item_weights(items: &[FrameItem], db: &Weights, e: usize) -> Result<Weights, String> {
    let mut data = Vec::with_capacity(items.len() * e);
    for item in items {
        let r: &[f32] = match item {
            FrameItem::Frame(f) => {
                db.row(*f as usize).ok_or_else(|| format!("frame {f} is past the database's {} frames", db.frames))?
            }
            FrameItem::Weights(w) => w,
        };
        data.extend((0..e).map(|c| r.get(c).copied().unwrap_or(0.0)));
    }
    Weights::new(items.len(), e, data).ok_or_else(|| "weights size mismatch".into())
}

/// Frames reconstructed per matrix product in [`frames_to_samples`].
const RECONSTRUCT_BATCH: usize = 64;

/// Reconstructs every item of a frame list with the first `e` eigenfires (eq. 22), in batches.
pub fn frames_to_samples(basis: &Basis, db: &Weights, items: &[FrameItem], e: usize) -> Result<Vec<f32>, String> {
    let mut out = Vec::with_capacity(items.len() * basis.pixels());
    for chunk in items.chunks(RECONSTRUCT_BATCH) {
        let w = item_weights(chunk, db, e)?;
        out.extend(reconstruct(basis, &w, e)?);
    }
    Ok(out)
}

pyrograph_core::choice! {
    /// How `eigen.frames_to_clip` turns database frames into images.
    pub enum ClipMode {
        /// Reconstruct every frame from its weights (eq. 22).
        Reconstruct = "reconstruct",
        /// Fetch database frames from the training clips (§7.1.2).
        Source = "source",
    }
}

pyrograph_core::node! {
    /// Turns a frame list into a clip by reconstruction (thesis §4.8, eq. 22) or from the source clips (§7.1.2).
    ///
    /// reconstruct: every frame is I = eigenfire Ω + Ψ with `components` eigenfires (the E for rendering), in
    /// batched matrix products. source: database frames are fetched from the connected training clips (the
    /// "modified video" trick: pre/post-processed originals, no reconstruction; clip1..3 as in
    /// eigen.eigenfires), and synthesized weights are still reconstructed.
    #[node("eigen.frames_to_clip", "Eigenfires", WholeClip)]
    pub struct FramesToClip {
        /// The animation.
        frames: Arc<FrameList>,
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// The database's training weights.
        weights: Arc<Weights>,
        /// How database frames become images.
        mode: ClipMode = ClipMode::Reconstruct,
        /// E for rendering; 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Source clip 1 (mode source).
        clip1: ClipOf<Arc<Image>> = ClipOf::new(empty_clip()),
        /// Source clip 2 (mode source).
        clip2: ClipOf<Arc<Image>> = ClipOf::new(empty_clip()),
        /// Source clip 3 (mode source).
        clip3: ClipOf<Arc<Image>> = ClipOf::new(empty_clip()),
        /// Clamp reconstructed samples to 0..1.
        clamp: bool = true,
        /// Frame rate of the clip.
        #[range(0.001, 1000.0)]
        fps: f64 = 30.0,
    }
    /// The frames.
    -> clip: ClipOf<Arc<Image>>
}

impl Cook for FramesToClip {
    fn cook(self, ctx: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        let (list, basis, db) = (&*self.frames, &*self.basis, &*self.weights);
        let frames_port = port!(FramesToClip, frames);
        if list.items.is_empty() {
            return Err(NodeError::port(frames_port, "the frame list is empty"));
        }
        let e = components_to_use(self.components, basis.components().min(db.components))
            .map_err(|m| NodeError::port(port!(FramesToClip, components), m))?;
        let (clamp, fps) = (self.clamp, self.fps);
        let rendered = |items: &[FrameItem]| -> Result<Clip, NodeError> {
            let samples = frames_to_samples(basis, db, items, e).map_err(|m| NodeError::port(frames_port, m))?;
            samples_to_clip(basis, samples, clamp, fps).map_err(NodeError::msg)
        };
        if self.mode == ClipMode::Reconstruct {
            return Ok(ClipOf::new(rendered(&list.items)?));
        }
        let clips: [(&str, &Clip); 3] = [
            (port!(FramesToClip, clip1), &*self.clip1),
            (port!(FramesToClip, clip2), &*self.clip2),
            (port!(FramesToClip, clip3), &*self.clip3),
        ];
        let synth: Vec<FrameItem> = list.items.iter().filter(|x| matches!(x, FrameItem::Weights(_))).cloned().collect();
        let synth_clip = if synth.is_empty() { None } else { Some(rendered(&synth)?) };
        let mut synth_index = Vec::with_capacity(list.items.len());
        let mut k = 0;
        for item in &list.items {
            synth_index.push(if matches!(item, FrameItem::Weights(_)) {
                k += 1;
                Some(k - 1)
            } else {
                None
            });
        }
        let frames = list
            .items
            .par_iter()
            .zip(&synth_index)
            .map(|(item, s)| match (item, s, &synth_clip) {
                (_, Some(s), Some(c)) => c.get(*s, ctx),
                (FrameItem::Frame(f), _, _) => {
                    let src = basis
                        .sources
                        .get(*f as usize)
                        .ok_or_else(|| NodeError::port(frames_port, format!("frame {f} is past the database's frames")))?;
                    let &(port, clip) = clips
                        .get(src.clip as usize)
                        .ok_or_else(|| NodeError::port(frames_port, format!("no input clip{}", src.clip + 1)))?;
                    if clip.len() <= src.index as usize {
                        return Err(NodeError::port(
                            port,
                            format!(
                                "database frame {f} is frame {} of training clip {}; connect that clip here",
                                src.index,
                                src.clip + 1
                            ),
                        ));
                    }
                    clip.get(src.index as usize, ctx)
                }
                _ => Err(NodeError::msg("inconsistent frame list")),
            })
            .collect::<Vec<_>>();
        // Sequential so the error reported is the first in list order, not whichever thread lost.
        let frames = frames.into_iter().collect::<Result<Vec<_>, _>>()?;
        Ok(ClipOf::new(Clip::from_frames(PortType::Image, fps, frames)))
    }
}

/// Parses `"2=1.5, 3=-0.8"` (1-based component = value).
pub fn parse_edits(text: &str, components: usize) -> Result<Vec<(usize, f64)>, String> {
    text.split([',', ';', '\n'])
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            let (k, v) = s.split_once('=').ok_or_else(|| format!("'{s}' is not of the form COMPONENT=VALUE"))?;
            let k: usize = k.trim().parse().map_err(|_| format!("'{}' is not a component number", k.trim()))?;
            let v: f64 = v.trim().parse().map_err(|_| format!("'{}' is not a number", v.trim()))?;
            if k == 0 || k > components {
                return Err(format!("component {k} does not exist: the basis has 1..={components}"));
            }
            Ok((k, v))
        })
        .collect()
}

/// §5.2: a weight vector starting from database frame `frame` (or zeros, the mean image), with
/// `edits` applied (set or added), values in absolute weights or in standard deviations √λ_k.
pub fn edit_weights(
    basis: &Basis,
    db: &Weights,
    frame: Option<usize>,
    edits: &[(usize, f64)],
    sigma: bool,
    add: bool,
) -> Result<Vec<f32>, String> {
    let e = basis.components();
    let mut w = match frame {
        Some(f) => {
            let r = db.row(f).ok_or_else(|| format!("frame {f} is past the database's {} frames", db.frames))?;
            (0..e).map(|c| r.get(c).copied().unwrap_or(0.0)).collect()
        }
        None => vec![0.0_f32; e],
    };
    for &(k, v) in edits {
        let v = if sigma { v * basis.eigenvalues[k - 1].sqrt() } else { v } as f32;
        w[k - 1] = if add { w[k - 1] + v } else { v };
    }
    Ok(w)
}

pyrograph_core::choice! {
    /// The units of `eigen.weights_edit`'s values.
    pub enum Units {
        /// Standard deviations √λ_k.
        Sigma = "sigma",
        /// Raw weights.
        Absolute = "absolute",
    }
}

pyrograph_core::choice! {
    /// Whether `eigen.weights_edit` replaces the weights or adds to them.
    pub enum EditMode {
        /// Replace the weights.
        Set = "set",
        /// Add to them.
        Add = "add",
    }
}

pyrograph_core::node! {
    /// Synthesizes a flame by setting eigenfire weights by hand (thesis §5.2, Fig. 44).
    ///
    /// Starts from database frame `frame`, or from all zeros (the mean image) when frame is -1, then sets (or
    /// adds) the listed weights, e.g. "2=1.5, 3=-0.8, 50=0.1". In sigma units a value is multiplied by √λ_k,
    /// the spread of that weight over the training set. Feed the result to eigen.reconstruct.
    #[node("eigen.weights_edit", "Eigenfires", Source)]
    pub struct WeightsEdit {
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// The database's training weights (for frame).
        weights: Arc<Weights>,
        /// Database frame to start from; -1 = zeros (mean image).
        #[range(-1, 100_000_000)]
        frame: i64 = -1,
        /// COMPONENT=VALUE pairs, 1-based, comma separated.
        edits: String = String::new(),
        /// Values in standard deviations √λ_k or raw weights.
        units: Units = Units::Sigma,
        /// Replace the weights or add to them.
        mode: EditMode = EditMode::Set,
    }
    /// One row of weights.
    -> weights: Arc<Weights>
}

impl Cook for WeightsEdit {
    fn cook(self, _: &CookCtx) -> Result<Arc<Weights>, NodeError> {
        let (basis, db) = (&*self.basis, &*self.weights);
        let edits = parse_edits(&self.edits, basis.components()).map_err(|m| NodeError::port(port!(WeightsEdit, edits), m))?;
        // -1 (any negative frame) starts from zeros.
        let frame = usize::try_from(self.frame).ok();
        let w = edit_weights(basis, db, frame, &edits, self.units == Units::Sigma, self.mode == EditMode::Add)
            .map_err(|m| NodeError::port(port!(WeightsEdit, frame), m))?;
        let n = w.len();
        let w = Weights::new(1, n, w).ok_or_else(|| NodeError::msg("weights size mismatch"))?;
        Ok(Arc::new(w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line_db(n: usize) -> Weights {
        Weights::new(n, 2, (0..n).flat_map(|i| [i as f32, 0.0]).collect()).unwrap()
    }

    #[test]
    #[allow(clippy::reversed_empty_ranges)]
    fn cut_scenario_plays_motions_in_order_and_loop_trims_for_lowpass() {
        let db = line_db(20);
        let items = motion_list(&db, &[0..=2, 10..=11], false, &Method::Cut).unwrap();
        assert_eq!(items, [0, 1, 2, 10, 11].map(FrameItem::Frame).to_vec());
        let lp = Method::LowPass { components: 2, kernel: vec![1.0 / 3.0; 3], span: 1 };
        let items = motion_list(&db, &[0..=3, 10..=13], true, &lp).unwrap();
        // 4 + 4 frames, each seam replaces one frame either side with two morphs: same length.
        assert_eq!(items.len(), 8);
        assert_eq!(items[0], FrameItem::Frame(1), "the loop's morph replaces the first frame");
        assert!(matches!(items[3], FrameItem::Weights(_)));
        let err = motion_list(&db, &[5..=3], false, &Method::Cut).unwrap_err();
        assert!(err.contains("empty"), "{err}");
        let lp2 = Method::LowPass { components: 2, kernel: vec![1.0 / 3.0; 3], span: 2 };
        assert!(motion_list(&db, &[0..=1, 5..=6], false, &lp2).unwrap_err().contains("too short"));
    }

    #[test]
    fn motions_and_scenarios_parse_with_clear_errors() {
        let m = parse_motions("T1 = 100-180; T2 = 2000-2050").unwrap();
        assert_eq!(m[1], ("T2".to_string(), 2000..=2050));
        let s = parse_scenario("T1 + T2 + T1", &m).unwrap();
        assert_eq!(s.len(), 3);
        assert!(parse_scenario("T3", &m).unwrap_err().contains("unknown motion 'T3'"));
        assert!(parse_motions("T1 100").is_err());
    }

    #[test]
    fn weight_edits_set_and_add_in_sigma_units() {
        let basis = Basis {
            width: 1,
            height: 1,
            mean: vec![0.0],
            eigenvectors: vec![1.0, 0.0],
            eigenvalues: vec![4.0, 1.0],
            sources: vec![],
        };
        let db = Weights::new(1, 2, vec![1.0, 1.0]).unwrap();
        let e = parse_edits("1=2, 2=-1", 2).unwrap();
        assert_eq!(edit_weights(&basis, &db, None, &e, true, false).unwrap(), vec![4.0, -1.0]);
        assert_eq!(edit_weights(&basis, &db, Some(0), &e, false, true).unwrap(), vec![3.0, 0.0]);
        assert!(parse_edits("3=1", 2).unwrap_err().contains("1..=2"));
    }
}
