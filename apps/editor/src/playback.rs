//! The preview's player. In real time (the default, like Houdini's "Realtime" toggle and Nuke's
//! viewer) frame k of a play is due k frame periods after Play was pressed; when a cook makes the
//! player late it skips to the frame the clock is on and counts the frames it dropped. With real
//! time off it shows every frame, each as soon as the one before it has cooked (how fast a preset
//! can play).

use std::time::{Duration, Instant};

/// Play state of the preview.
#[derive(Clone, Debug)]
pub struct Playback {
    /// Whether the preview is playing.
    pub playing: bool,
    /// Keep to the clip's frame rate, dropping frames when late (on), or show every frame as
    /// fast as it cooks (off).
    pub realtime: bool,
    /// Frames skipped to keep time since Play was last pressed.
    pub dropped: u64,
    clock: Option<Clock>,
}

/// When a real-time play started and how far it has got.
#[derive(Clone, Copy, Debug)]
struct Clock {
    start: Instant,
    /// The frame shown when Play was pressed.
    first: usize,
    /// Frames advanced since then (not wrapped).
    shown: u64,
}

impl Default for Playback {
    fn default() -> Self {
        Playback { playing: false, realtime: true, dropped: 0, clock: None }
    }
}

impl Playback {
    /// Starts or stops playing; a new play starts its clock at the frame shown.
    pub fn set_playing(&mut self, playing: bool) {
        if playing && !self.playing {
            self.dropped = 0;
        }
        self.playing = playing;
        self.clock = None;
    }

    /// Play / pause.
    pub fn toggle(&mut self) {
        self.set_playing(!self.playing);
    }

    /// Sets real time on or off; the clock restarts at the frame shown.
    pub fn set_realtime(&mut self, realtime: bool) {
        self.realtime = realtime;
        self.clock = None;
    }

    /// What the player does at `now`, with frame `current` of a clip of `len` frames at `fps`
    /// shown and a cook running or not: the frame to ask for, if any, and how long until it wants
    /// to look again (`None`: when the running cook finishes, which repaints anyway).
    pub fn step(
        &mut self,
        now: Instant,
        current: usize,
        len: usize,
        fps: f64,
        cooking: bool,
    ) -> (Option<usize>, Option<Duration>) {
        if !self.playing {
            return (None, None);
        }
        if len == 0 {
            self.set_playing(false);
            return (None, None);
        }
        if cooking {
            // The frame asked for is not there yet: wait for it (its arrival repaints).
            return (None, None);
        }
        if !self.realtime {
            return (Some((current + 1) % len), None);
        }
        let period = 1.0 / if fps.is_finite() && fps > 0.0 { fps } else { 24.0 };
        let clock = self.clock.get_or_insert(Clock { start: now, first: current, shown: 0 });
        let due = (now.saturating_duration_since(clock.start).as_secs_f64() / period).floor() as u64;
        let mut ask = None;
        if due > clock.shown {
            self.dropped += due - clock.shown - 1;
            clock.shown = due;
            ask = Some(((clock.first as u64 + due) % len as u64) as usize);
        }
        let next = clock.start + Duration::from_secs_f64((clock.shown + 1) as f64 * period);
        (ask, Some(next.saturating_duration_since(now)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(start: Instant, periods: f64) -> Instant {
        start + Duration::from_secs_f64(periods / 24.0)
    }

    #[test]
    fn real_time_keeps_to_the_clock_and_counts_the_frames_it_skips() {
        let t0 = Instant::now();
        let mut p = Playback::default();
        p.set_playing(true);
        // Pressed on frame 5: nothing is due until one period has passed.
        let (ask, wake) = p.step(t0, 5, 48, 24.0, false);
        assert_eq!(ask, None);
        assert!((wake.unwrap().as_secs_f64() - 1.0 / 24.0).abs() < 1e-6, "{wake:?}");
        assert_eq!(p.step(at(t0, 1.2), 5, 48, 24.0, false).0, Some(6));
        // The cook of frame 6 ran long: nothing is asked while it runs ...
        assert_eq!(p.step(at(t0, 3.5), 5, 48, 24.0, true), (None, None));
        // ... and once it is in, the player jumps to the frame the clock is on: 7 and 8 dropped.
        let (ask, wake) = p.step(at(t0, 4.1), 6, 48, 24.0, false);
        assert_eq!(ask, Some(9));
        assert_eq!(p.dropped, 2);
        assert!((wake.unwrap().as_secs_f64() - 0.9 / 24.0).abs() < 1e-6, "{wake:?}");
        // On time: no drops, and the clip wraps.
        let mut q = Playback::default();
        q.set_playing(true);
        q.step(t0, 46, 48, 24.0, false);
        assert_eq!(q.step(at(t0, 1.01), 46, 48, 24.0, false).0, Some(47));
        assert_eq!(q.step(at(t0, 2.01), 47, 48, 24.0, false).0, Some(0));
        assert_eq!(q.dropped, 0);
    }

    #[test]
    fn off_real_time_every_frame_follows_the_last_cook() {
        let t0 = Instant::now();
        let mut p = Playback::default();
        p.set_realtime(false);
        assert_eq!(p.step(t0, 3, 10, 24.0, false), (None, None), "not playing");
        p.toggle();
        assert_eq!(p.step(t0, 3, 10, 24.0, false), (Some(4), None));
        assert_eq!(p.step(at(t0, 9.0), 4, 10, 24.0, true), (None, None), "waits for the cook however long");
        assert_eq!(p.step(at(t0, 9.0), 9, 10, 24.0, false), (Some(0), None));
        assert_eq!(p.dropped, 0);
        // An empty clip stops the player.
        assert_eq!(p.step(t0, 0, 0, 24.0, false), (None, None));
        assert!(!p.playing);
    }

    #[test]
    fn pressing_play_again_restarts_the_clock_and_the_count() {
        let t0 = Instant::now();
        let mut p = Playback::default();
        p.set_playing(true);
        p.step(t0, 0, 100, 24.0, false);
        p.step(at(t0, 10.01), 0, 100, 24.0, false);
        assert_eq!(p.dropped, 9);
        p.toggle();
        p.toggle();
        assert_eq!(p.dropped, 0);
        let t1 = at(t0, 20.0);
        assert_eq!(p.step(t1, 10, 100, 24.0, false).0, None, "the new clock starts at the frame shown");
        assert_eq!(p.step(at(t1, 1.01), 10, 100, 24.0, false).0, Some(11));
    }
}
