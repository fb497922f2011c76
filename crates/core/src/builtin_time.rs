//! Time and math nodes: clips of the frame number, the time and a keyframed curve, and the small
//! per-frame maths (fit, clamp, mix, sine, noise) that shape them into any parameter. A clip into
//! a per-frame node's Float input lifts that node, so these drive parameters the way an
//! expression does, but as nodes an artist can see and rewire.
//!
//! The clips are lazy and compute frame `i` from `i` alone, so a frame cooked on its own (a farm
//! task's chunk) equals the same frame of a full cook. Each frame is keyed by its value, so a
//! node downstream of a moved key re-cooks only the frames whose value moved.

use std::f64::consts::TAU;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use crate::ctx::CookCtx;
use crate::declare::{Anim, ClipOf, Cook, Port};
use crate::error::NodeError;
use crate::fingerprint::Fingerprinter;
use crate::timeline::Timeline;
use crate::value::{Clip, FrameSource, PortType, Value};

/// The time and math node types, for the core's list of built-ins.
pub fn nodes() -> Vec<Arc<dyn crate::node::Node>> {
    vec![TimeFrame::node(), TimeChannel::node(), Fit::node(), Clamp::node(), Mix::node(), Sine::node(), Noise::node()]
}

/// Bound of the numbers: wide, but finite so sliders have ends (as the other math nodes).
const BIG: f64 = 1e12;

// ---------------------------------------------------------------------------------------------
// Time

crate::node! {
    /// The frame number and the time in seconds of every frame of a timeline, as clips: connect
    /// either to a per-frame node's Float input to drive it over time.
    #[node("time.frame", "Time", Source)]
    pub struct TimeFrame {
        /// The clips' length and rate.
        timeline: Timeline,
    }
    pub struct TimeFrameOut {
        /// The frame number: frame i is i (0, 1, 2, …).
        frame: ClipOf<f64>,
        /// The time in seconds: frame i is i / fps (an expression's `time`).
        time: ClipOf<f64>,
    }
}

impl Cook for TimeFrame {
    fn cook(self, _: &CookCtx) -> Result<TimeFrameOut, NodeError> {
        let Timeline { frames, fps } = self.timeline;
        Ok(TimeFrameOut {
            frame: ClipOf::new(Timed { what: What::Frame, frames, fps }.clip()),
            time: ClipOf::new(Timed { what: What::Seconds, frames, fps }.clip()),
        })
    }
}

crate::node! {
    /// A keyframed curve or an expression as a clip any node can take: frame i is the value
    /// sampled at frame i. Set `value` to `keys([...])` or `expr("...")` in the graph file.
    #[node("time.channel", "Time", Source)]
    pub struct TimeChannel {
        /// The clip's length and rate (the rate is the `fps` expressions see).
        timeline: Timeline,
        /// The curve: a constant, `keys([(frame, value), …])` or `expr("…")`.
        #[range(-BIG, BIG)]
        value: Anim<f64> = Anim::constant(0.0),
    }
    /// The curve sampled at every frame.
    -> value: ClipOf<f64>
}

impl Cook for TimeChannel {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<f64>, NodeError> {
        let Timeline { frames, fps } = self.timeline;
        Ok(ClipOf::new(Timed { what: What::Channel(self.value), frames, fps }.clip()))
    }
}

/// What a time node's clip holds at each frame.
#[derive(Clone, Debug)]
enum What {
    /// The frame number.
    Frame,
    /// The frame's time in seconds.
    Seconds,
    /// A curve sampled at the frame.
    Channel(Anim<f64>),
}

/// The frames of a time node's clip, computed on demand from the frame number alone.
struct Timed {
    what: What,
    frames: usize,
    fps: f64,
}

impl Timed {
    /// Frame `index`'s value; a channel's error names the port and the frame.
    fn value(&self, index: usize) -> Result<f64, NodeError> {
        let frame = index as f64;
        match &self.what {
            What::Frame => Ok(frame),
            What::Seconds => Ok(frame / self.fps),
            What::Channel(curve) => Ok(curve.at(frame, self.fps)?),
        }
    }

    /// The lazy clip. Its fingerprint covers everything a frame depends on, so a changed key or
    /// timeline re-cooks the consumers (whose frames the content keys then mostly serve).
    fn clip(self) -> Clip {
        let mut h = Fingerprinter::new();
        match &self.what {
            What::Frame => "frame".hash(&mut h),
            What::Seconds => "seconds".hash(&mut h),
            What::Channel(curve) => {
                "channel".hash(&mut h);
                curve.clone().into_value().hash_into(&mut h);
            }
        }
        (self.frames, self.fps.to_bits()).hash(&mut h);
        Clip::new(PortType::Float, self.fps, h.finish(), Arc::new(self))
    }
}

impl FrameSource for Timed {
    fn len(&self) -> usize {
        self.frames
    }

    fn frame(&self, index: usize, _: &CookCtx) -> Result<Value, NodeError> {
        self.value(index).map(Value::Float)
    }

    /// The frame's value itself: equal values are the same frame, wherever they come from.
    fn frame_key(&self, index: usize) -> Option<u64> {
        self.value(index).ok().map(|x| Value::Float(x).fingerprint())
    }
}

// ---------------------------------------------------------------------------------------------
// Math

crate::node! {
    /// Maps x from one range to another (Houdini's `fit`): from_min goes to to_min, from_max to
    /// to_max. An empty input range (from_min = from_max) is a step at from_min.
    #[node("math.fit", "Math", PerFrame)]
    pub struct Fit {
        /// The value to map.
        #[range(-BIG, BIG)]
        x: f64 = 0.0,
        /// The input range's start.
        #[range(-BIG, BIG)]
        from_min: f64 = 0.0,
        /// The input range's end.
        #[range(-BIG, BIG)]
        from_max: f64 = 1.0,
        /// The output range's start.
        #[range(-BIG, BIG)]
        to_min: f64 = 0.0,
        /// The output range's end.
        #[range(-BIG, BIG)]
        to_max: f64 = 1.0,
        /// Keep the result within the output range (off: continue the line beyond it).
        clamp: bool = true,
    }
    /// The mapped value.
    -> value: f64
}

impl Cook for Fit {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        let value = fit(self.x, self.from_min, self.from_max, self.to_min, self.to_max, self.clamp);
        // Only an unclamped fit of a range a few ulps wide can overflow; say which range, not "inf".
        if !value.is_finite() {
            let message = format!(
                "from_min ({}) and from_max ({}) are so close that x = {} maps to {value}: widen the range or turn clamp on",
                self.from_min, self.from_max, self.x
            );
            return Err(NodeError::port(crate::port!(Fit, from_max), message));
        }
        Ok(value)
    }
}

/// `x` mapped from `a..b` to `c..d`; with `clamp` the same numbers as an expression's
/// `fit(x, a, b, c, d)`, so a graph can move a formula into nodes without changing a frame.
fn fit(x: f64, a: f64, b: f64, c: f64, d: f64, clamp: bool) -> f64 {
    if clamp {
        return crate::anim::expr::fit(x, a, b, c, d);
    }
    // An empty input range is a step at `a` rather than 0/0, as in Houdini and the expressions.
    let t = if a == b { if x < a { 0.0 } else { 1.0 } } else { (x - a) / (b - a) };
    c + t * (d - c)
}

crate::node! {
    /// Limits x to min..max.
    #[node("math.clamp", "Math", PerFrame)]
    pub struct Clamp {
        /// The value to limit.
        #[range(-BIG, BIG)]
        x: f64 = 0.0,
        /// The lowest result.
        #[range(-BIG, BIG)]
        min: f64 = 0.0,
        /// The highest result.
        #[range(-BIG, BIG)]
        max: f64 = 1.0,
    }
    /// x, limited.
    -> value: f64
}

impl Cook for Clamp {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        // Refused rather than picking one bound: swapped bounds are almost always a wiring mistake,
        // and a silent choice would hide it.
        if self.min > self.max {
            let message = format!("min ({}) is above max ({}): swap them, or lower min", self.min, self.max);
            return Err(NodeError::port(crate::port!(Clamp, min), message));
        }
        Ok(self.x.clamp(self.min, self.max))
    }
}

crate::node! {
    /// Blends from a to b by t: a + (b − a)·t. t = 0 gives a, t = 1 gives b; beyond them the
    /// line continues.
    #[node("math.mix", "Math", PerFrame)]
    pub struct Mix {
        /// The value at t = 0.
        #[range(-BIG, BIG)]
        a: f64 = 0.0,
        /// The value at t = 1.
        #[range(-BIG, BIG)]
        b: f64 = 1.0,
        /// The blend.
        #[range(-BIG, BIG)]
        t: f64 = 0.5,
    }
    /// The blend of a and b.
    -> value: f64
}

impl Cook for Mix {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.a + (self.b - self.a) * self.t)
    }
}

crate::node! {
    /// A sine wave of x: amplitude·sin(2π(frequency·x + phase)) + offset. With x the time in
    /// seconds, frequency is in cycles per second.
    #[node("math.sine", "Math", PerFrame)]
    pub struct Sine {
        /// Where on the wave (a frame number or a time).
        #[range(-BIG, BIG)]
        x: f64 = 0.0,
        /// Cycles per unit of x.
        #[range(-BIG, BIG)]
        frequency: f64 = 1.0,
        /// Half the distance from trough to crest.
        #[range(-BIG, BIG)]
        amplitude: f64 = 1.0,
        /// Shift along the wave, in cycles (0.25 turns the sine into a cosine).
        #[range(-BIG, BIG)]
        phase: f64 = 0.0,
        /// Added to the wave: its middle value.
        #[range(-BIG, BIG)]
        offset: f64 = 0.0,
    }
    /// The wave's value at x.
    -> value: f64
}

impl Cook for Sine {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.amplitude * (TAU * (self.frequency * self.x + self.phase)).sin() + self.offset)
    }
}

crate::node! {
    /// Smooth 1-D Perlin noise of x, in about −amplitude..amplitude: the same numbers as an
    /// expression's `noise(frequency * x, seed) * amplitude`.
    #[node("math.noise", "Math", PerFrame)]
    pub struct Noise {
        /// Where along the noise (a frame number or a time).
        #[range(-BIG, BIG)]
        x: f64 = 0.0,
        /// Features per unit of x; the pattern repeats every 256 / frequency.
        #[range(-BIG, BIG)]
        frequency: f64 = 1.0,
        /// Scale of the result.
        #[range(-BIG, BIG)]
        amplitude: f64 = 1.0,
        /// Which pattern: each seed gives an unrelated one.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
    /// The noise at x.
    -> value: f64
}

impl Cook for Noise {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        // The expressions' own noise, so the node and `noise(frequency * x, seed)` agree bit for bit.
        Ok(self.amplitude * crate::anim::expr::perlin(self.frequency * self.x, f64::from(self.seed)))
    }
}
