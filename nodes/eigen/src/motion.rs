//! Motion lists and scenarios (thesis §5.1, Figs. 32–33), turning frame lists into clips (§4.8
//! reconstruction, or §7.1.2 "modified video": fetching the source frames), and weight synthesis
//! by hand (§5.2).

use std::ops::RangeInclusive;
use std::sync::Arc;

use pyrograph_core::{
    Basis, Clip, CookCtx, FnNode, FrameItem, FrameList, Inputs, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep,
    Value, Weights,
};
use rayon::prelude::*;

use crate::pca::{components_to_use, optional_clip_port, reconstruct, samples_to_clip};
use crate::transition::{
    check_range, direct_bridging, end_exclusion, end_growing, exclusion_mask, lowpass_kernel, lowpass_transition,
};

/// Adds this module's node types.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(motion_list_desc(), cook_motion_list));
    registry.add(FnNode::new(frames_to_clip_desc(), cook_frames_to_clip));
    registry.add(FnNode::new(weights_edit_desc(), cook_weights_edit));
}

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

fn motion_list_desc() -> NodeDesc {
    NodeDesc::new(
        "eigen.motion_list",
        "Eigenfires",
        TimeDep::WholeClip,
        "Builds an animation from named motions and a scenario, joined by a motion transition (thesis §5.1, Figs. 32–33).\n\n\
         motions names ranges of database frames (\"T1 = 100-180; T2 = 400-450\"); scenario plays them in order \
         (\"T1 + T2 + T1\"); loop adds a transition from the last back into the first. method: cut (plain \
         attachment), lowpass (§5.1.1; its morphed frames replace `span` frames each side of the seam), \
         direct_bridging (§5.1.2.1; `steps` frames, T1 and T2 frames excluded) or end_growing (§5.1.2.2; at most \
         `steps` frames).",
    )
    .input(PortDesc::new("weights", PortType::Weights, "The database's training weights."))
    .input(PortDesc::string("motions", "T1 = 0-49; T2 = 100-149", "Named motions: NAME = first-last; …"))
    .input(PortDesc::string("scenario", "T1 + T2", "Motions in playing order."))
    .input(PortDesc::bool("loop", false, "Join the end of the last motion back to the first."))
    .input(PortDesc::choice("method", &["cut", "lowpass", "direct_bridging", "end_growing"], "end_growing", "Transition method."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for detection (recognition methods); 0 = all."))
    .input(PortDesc::float("theta_min", 0.0, (0.0, 1e9), "Minimum threshold θ_min (recognition methods)."))
    .input(PortDesc::int("steps", 40, (1, 100_000), "Direct Bridging: frames inserted; End Growing: maximum frames."))
    .input(PortDesc::int("exclude", 7, (0, 100_000), "End Growing: frames at each motion's end/start that may not be picked."))
    .input(PortDesc::int("lowpass_components", 50, (1, 1_000_000), "Low-pass: components filtered."))
    .input(PortDesc::choice("kernel", &["box3", "box5", "end_weighted"], "box3", "Low-pass kernel."))
    .input(PortDesc::int("span", 2, (1, 10_000), "Low-pass: morphed frames each side of a seam."))
    .output("frames", PortType::FrameList, "The animation's frames.")
    .output("count", PortType::Int, "Number of frames.")
}

fn cook_motion_list(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let motions = parse_motions(i.string("motions")?).map_err(|m| NodeError::port("motions", m))?;
    for (name, r) in &motions {
        check_range(r, db.frames, &format!("motion {name}")).map_err(|m| NodeError::port("motions", m))?;
    }
    let segments = parse_scenario(i.string("scenario")?, &motions).map_err(|m| NodeError::port("scenario", m))?;
    let method = match i.choice("method")? {
        "cut" => Method::Cut,
        "lowpass" => Method::LowPass {
            components: components_to_use(i.usize("lowpass_components")?, db.components, "lowpass_components")?,
            kernel: lowpass_kernel(i.choice("kernel")?).map_err(|m| NodeError::port("kernel", m))?,
            span: i.usize("span")?,
        },
        "direct_bridging" => Method::DirectBridging {
            steps: i.usize("steps")?,
            components: components_to_use(i.usize("components")?, db.components, "components")?,
            theta_min: i.float("theta_min")?,
        },
        "end_growing" => Method::EndGrowing {
            steps: i.usize("steps")?,
            components: components_to_use(i.usize("components")?, db.components, "components")?,
            theta_min: i.float("theta_min")?,
            exclude: i.usize("exclude")?,
        },
        other => return Err(NodeError::port("method", format!("unknown method '{other}'"))),
    };
    let items = motion_list(db, &segments, i.bool("loop")?, &method).map_err(|m| NodeError::port("method", m))?;
    let n = items.len() as i64;
    Ok(vec![Value::FrameList(Arc::new(FrameList { items })), Value::Int(n)])
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

fn frames_to_clip_desc() -> NodeDesc {
    NodeDesc::new(
        "eigen.frames_to_clip",
        "Eigenfires",
        TimeDep::WholeClip,
        "Turns a frame list into a clip by reconstruction (thesis §4.8, eq. 22) or from the source clips (§7.1.2).\n\n\
         reconstruct: every frame is I = eigenfire Ω + Ψ with `components` eigenfires (the E for rendering), in \
         batched matrix products. source: database frames are fetched from the connected training clips (the \
         \"modified video\" trick: pre/post-processed originals, no reconstruction; clip1..3 as in \
         eigen.eigenfires), and synthesized weights are still reconstructed.",
    )
    .input(PortDesc::new("frames", PortType::FrameList, "The animation."))
    .input(PortDesc::new("basis", PortType::Basis, "The Eigenfires basis."))
    .input(PortDesc::new("weights", PortType::Weights, "The database's training weights."))
    .input(PortDesc::choice("mode", &["reconstruct", "source"], "reconstruct", "How database frames become images."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for rendering; 0 = all."))
    .input(optional_clip_port("clip1", "Source clip 1 (mode source)."))
    .input(optional_clip_port("clip2", "Source clip 2 (mode source)."))
    .input(optional_clip_port("clip3", "Source clip 3 (mode source)."))
    .input(PortDesc::bool("clamp", true, "Clamp reconstructed samples to 0..1."))
    .input(PortDesc::float("fps", 30.0, (0.001, 1000.0), "Frame rate of the clip."))
    .output("clip", PortType::clip_of(PortType::Image), "The frames.")
}

fn cook_frames_to_clip(i: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let list = i.frame_list("frames")?;
    let basis = i.basis("basis")?;
    let db = i.weights("weights")?;
    if list.items.is_empty() {
        return Err(NodeError::port("frames", "the frame list is empty"));
    }
    let e = components_to_use(i.usize("components")?, basis.components().min(db.components), "components")?;
    let (clamp, fps) = (i.bool("clamp")?, i.float("fps")?);
    let rendered = |items: &[FrameItem]| -> Result<Clip, NodeError> {
        let samples = frames_to_samples(basis, db, items, e).map_err(|m| NodeError::port("frames", m))?;
        samples_to_clip(basis, samples, clamp, fps)
    };
    if i.choice("mode")? == "reconstruct" {
        return Ok(vec![Value::Clip(rendered(&list.items)?)]);
    }
    let clips = [i.clip("clip1")?, i.clip("clip2")?, i.clip("clip3")?];
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
                    .ok_or_else(|| NodeError::port("frames", format!("frame {f} is past the database's frames")))?;
                let port = format!("clip{}", src.clip + 1);
                let clip = clips.get(src.clip as usize).ok_or_else(|| NodeError::port("frames", format!("no input {port}")))?;
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
    Ok(vec![Value::Clip(Clip::from_frames(PortType::Image, fps, frames))])
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

fn weights_edit_desc() -> NodeDesc {
    NodeDesc::new(
        "eigen.weights_edit",
        "Eigenfires",
        TimeDep::Source,
        "Synthesizes a flame by setting eigenfire weights by hand (thesis §5.2, Fig. 44).\n\n\
         Starts from database frame `frame`, or from all zeros (the mean image) when frame is -1, then sets (or \
         adds) the listed weights, e.g. \"2=1.5, 3=-0.8, 50=0.1\". In sigma units a value is multiplied by √λ_k, \
         the spread of that weight over the training set. Feed the result to eigen.reconstruct.",
    )
    .input(PortDesc::new("basis", PortType::Basis, "The Eigenfires basis."))
    .input(PortDesc::new("weights", PortType::Weights, "The database's training weights (for frame)."))
    .input(PortDesc::int("frame", -1, (-1, 100_000_000), "Database frame to start from; -1 = zeros (mean image)."))
    .input(PortDesc::string("edits", "", "COMPONENT=VALUE pairs, 1-based, comma separated."))
    .input(PortDesc::choice("units", &["sigma", "absolute"], "sigma", "Values in standard deviations √λ_k or raw weights."))
    .input(PortDesc::choice("mode", &["set", "add"], "set", "Replace the weights or add to them."))
    .output("weights", PortType::Weights, "One row of weights.")
}

fn cook_weights_edit(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let basis = i.basis("basis")?;
    let db = i.weights("weights")?;
    let edits = parse_edits(i.string("edits")?, basis.components()).map_err(|m| NodeError::port("edits", m))?;
    let frame = usize::try_from(i.int("frame")?).ok();
    let w = edit_weights(basis, db, frame, &edits, i.choice("units")? == "sigma", i.choice("mode")? == "add")
        .map_err(|m| NodeError::port("frame", m))?;
    let n = w.len();
    let w = Weights::new(1, n, w).ok_or_else(|| NodeError::msg("weights size mismatch"))?;
    Ok(vec![Value::Weights(Arc::new(w))])
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
