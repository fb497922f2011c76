//! The settings of a fit of the generic flame model ([`FitSettings`], the ports of
//! `flame_model.fit` after its clip) and what to do with a flame cut by the picture's edge.

pyrograph_core::ports! {
    /// Settings of the fit: the ports of `flame_model.fit` after its clip, with their defaults.
    #[derive(PartialEq)]
    pub struct FitSettings {
        /// Path samples N_p at equidistant heights (paper: 10).
        #[range(1, 64)]
        n_p: usize = 10,
        /// Width samples N_w at equidistant heights (paper: 10).
        #[range(1, 64)]
        n_w: usize = 10,
        // Fewer when the frames do not have that many independent variations.
        /// Eigenflames N_e (paper: 5); at most frames − 1 are available.
        #[range(1, 1000)]
        n_e: usize = 5,
        /// Height slices N_s measured per frame before sampling path and width.
        #[range(1, 512)]
        n_s: usize = 20,
        /// Width of the normalized images (eigenflame size).
        #[range(4, 1024)]
        norm_width: u32 = 64,
        /// Height of the normalized images (eigenflame size).
        #[range(4, 1024)]
        norm_height: u32 = 128,
        /// Gray values at or below this are background (a fraction of the clip's peak when relative_threshold is on).
        #[range(0.0, 1.0)]
        threshold: f32 = 0.08,
        // The median over frames of each frame's brightest pixel: 1 for footage whose flame core
        // clips (the shared candle), lower for darker footage, which then needs no retuning.
        /// The threshold is a fraction of the clip's peak brightness (the median of the frames' brightest pixels, at least 0.25).
        relative_threshold: bool = true,
        /// Plumes under this fraction of a frame's intensity are specks (removed); two larger ones skip the frame.
        #[range(0.0, 1.0)]
        min_plume: f64 = 0.05,
        // A uniform ellipse is 4σ long; real flames' faint tips pull σ in, hence 6.
        /// Flame height = this × σ along the main axis (second-order moment).
        #[range(0.5, 20.0)]
        height_sigmas: f64 = 6.0,
        /// The flame base lies this many σ below the centroid along the main axis.
        #[range(0.0, 10.0)]
        base_sigmas: f64 = 3.6,
        // The normalized image spans u ∈ −u_extent..u_extent.
        /// Half-width of the normalized image, in local widths (σ of a slice).
        #[range(0.5, 20.0)]
        u_extent: f64 = 3.0,
        // Heights covered by the normalized image: from −v_below to 1 + v_above flame heights.
        /// Normalized image margin below the base, in flame heights.
        #[range(0.0, 2.0)]
        v_below: f64 = 0.12,
        /// Normalized image margin above the tip, in flame heights.
        #[range(0.0, 2.0)]
        v_above: f64 = 0.2,
        /// Scale every normalized image to the clip's average intensity (§3.1).
        normalize_intensity: bool = true,
        /// A clip whose flame base is outside the picture in a quarter of its frames or more: refuse to fit (the
        /// model needs the whole flame, base at the bottom, §3), or fit it with a warning.
        cut_base: CutBase = CutBase::Refuse,
        // A frame far from the others (a bad mask, a merged second plume) pulls the eigenflames
        // towards it; dropped, it leaves a gap in the series as a skipped two-plume frame does.
        // Frames are scored against eigenflames trained on them all, so a single strong outlier
        // may take an eigenflame of its own and score well: this catches frames unlike most.
        /// Drop frames whose normalized image the eigenflames reconstruct with a relative error above this (0 = keep all).
        #[range(0.0, 10.0)]
        max_residual: f64 = 0.0,
    }
}

pyrograph_core::choice! {
    /// What `flame_model.fit` does with a clip whose flame base is outside the picture.
    pub enum CutBase {
        /// Refuse with an error naming the edge and the share of frames.
        Refuse = "refuse",
        /// Fit anyway and report a warning.
        Warn = "warn",
    }
}

impl FitSettings {
    /// The normalized image size (width, height).
    pub fn norm_size(&self) -> (u32, u32) {
        (self.norm_width, self.norm_height)
    }
}
