//! When the GI cache restarts its entries and how many update iterations a frame runs: a pure function of what
//! changed, kept apart from the buffers so it can be tested on the CPU.
//!
//! - A change of light (a lamp placed or removed, a moving object appearing or going, the lighting mode, time
//!   of day, sun or shadows) restarts the entries: their direct light from several samples, their indirect light
//!   from zero with `RESTART_ITERATIONS` bounces in this one frame, so nothing of the old light is left to drain
//!   (a blend restarted from last frame's values drains a switched-off lamp over many frames at the game's blend
//!   weight: docs/bench/denoise.md).
//! - A fresh cache's entries are all young: each frame's light travels one bounce more and their blends average
//!   what came before, so a room lit over many bounces starts dark. For `WARM_UP_FRAMES` frames it runs
//!   `WARM_UP_ITERATIONS` iterations a frame to bring the next bounces within the same frame.
//! - An edit changes the light of every entry near it, most of them a bounce or two away from the edit itself:
//!   their blends restart for `EDIT_RESTART_FRAMES` frames (`GI_EDIT_RESTART`) so the new light is not averaged
//!   with the frames it takes to arrive (docs/bench/gi.md).

use crate::settings::{Lighting, RenderSettings, SEED_FRAMES};

/// Update iterations (update + filter, each one bounce more) in the frame after a change of light, started from
/// zero indirect light (GI_RESTART): the frame shows the new light with this many bounces and none of the old.
pub const RESTART_ITERATIONS: u32 = 4;
/// Frames of a fresh cache's warm-up (a world loaded, the cache's shape or seed changed), and its update
/// iterations a frame.
pub const WARM_UP_FRAMES: u32 = 64;
pub const WARM_UP_ITERATIONS: u32 = 4;
/// Frames the entries an edit reached restart their blends.
pub const EDIT_RESTART_FRAMES: u32 = 6;
/// Frame numbering starts here so that "last seen at frame 0" (a fresh entry) is never recent.
const FIRST_FRAME: u32 = 1000;

/// The light the entries were blended under; any change restarts them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightingKey {
    mode: Lighting,
    time_of_day_bits: u32,
    sun: bool,
    shadows: bool,
}

impl LightingKey {
    pub fn of(settings: &RenderSettings) -> Self {
        LightingKey {
            mode: settings.lighting,
            time_of_day_bits: settings.time.to_bits(),
            sun: settings.sun,
            shadows: settings.shadows,
        }
    }
}

/// What happened since last frame, as the schedule sees it.
#[derive(Clone, Copy, Debug)]
pub struct FrameEvents {
    pub lighting: LightingKey,
    /// The light pool changed (a lamp placed or removed).
    pub lights_changed: bool,
    /// A moving object appeared or went (a lantern's core is in no light pool).
    pub objects_came_or_went: bool,
    /// This frame's edits reached the edit log.
    pub edited: bool,
    /// The `gi_warm_up` setting.
    pub warm_up: bool,
}

impl FrameEvents {
    /// These events followed by `later`'s, as one frame sees them: any change in either.
    fn then(self, later: FrameEvents) -> FrameEvents {
        FrameEvents {
            lighting: later.lighting,
            lights_changed: self.lights_changed || later.lights_changed,
            objects_came_or_went: self.objects_came_or_went || later.objects_came_or_went,
            edited: self.edited || later.edited,
            warm_up: later.warm_up,
        }
    }
}

/// What this frame runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GiPlan {
    /// The entries restart (`GI_RESTART`).
    pub restart: bool,
    /// The entries an edit reached restart their blends (`GI_EDIT_RESTART`).
    pub edit_restart: bool,
    /// Update iterations this frame.
    pub iterations: u32,
    /// The frame number the shaders see (offset per seed).
    pub frame: u32,
    /// Update iterations run before this frame's (offset per seed): where fresh rays continue the entries'
    /// low-discrepancy sequences.
    pub update_run: u32,
}

impl GiPlan {
    /// Frames between two updates of a settled entry (the `gi_period` setting), or 1 while the light is new: after
    /// a change of light, during a fresh cache's warm-up and in the frames an edit restarts, every entry updates
    /// every frame so the new light reaches all of them at once.
    pub fn settled_period(&self, setting: u32) -> u32 {
        if self.restart || self.edit_restart || self.iterations > 1 { 1 } else { setting.max(1) }
    }
}

/// The schedule's state from frame to frame.
pub struct GiSchedule {
    lighting: Option<LightingKey>,
    /// The `seed` the entries were blended under: their frame stamps count from it.
    seed: u32,
    warm_up_frames: u32,
    edit_restart_frames: u32,
    frame: u32,
    update_run: u32,
    restarts: u32,
    /// Events of frames the cache did not run in (its pipelines still compiling), for the next frame it runs.
    held: Option<FrameEvents>,
}

impl Default for GiSchedule {
    fn default() -> Self {
        GiSchedule {
            lighting: None,
            seed: 0,
            warm_up_frames: WARM_UP_FRAMES,
            edit_restart_frames: 0,
            frame: FIRST_FRAME,
            update_run: 0,
            restarts: 0,
            held: None,
        }
    }
}

impl GiSchedule {
    /// Whether a cache for `seed` must start over (the entries' frame stamps count from the seed).
    pub fn seed_changed(&self, seed: u32) -> bool {
        self.seed != seed
    }

    /// A fresh cache (new world, new table shape or seed): its warm-up starts.
    pub fn start_fresh(&mut self, seed: u32) {
        self.seed = seed;
        self.warm_up_frames = WARM_UP_FRAMES;
    }

    /// Frames that restarted the entries after a change of light.
    pub fn restarts(&self) -> u32 {
        self.restarts
    }

    /// A frame the cache does not run in: nothing advances (a fresh cache's restart and warm-up wait for its
    /// first real frame), and what happened reaches the next frame that runs.
    pub fn hold(&mut self, events: FrameEvents) {
        self.held = Some(self.held.map_or(events, |held| held.then(events)));
    }

    /// Advances one frame.
    pub fn plan(&mut self, events: FrameEvents) -> GiPlan {
        let events = self.held.take().map_or(events, |held| held.then(events));
        let restart = events.lights_changed || events.objects_came_or_went || self.lighting != Some(events.lighting);
        self.lighting = Some(events.lighting);
        self.restarts += restart as u32;
        let iterations = if restart {
            RESTART_ITERATIONS
        } else if self.warm_up_frames > 0 && events.warm_up {
            WARM_UP_ITERATIONS
        } else {
            1
        };
        self.warm_up_frames = self.warm_up_frames.saturating_sub(1);
        if events.edited {
            self.edit_restart_frames = EDIT_RESTART_FRAMES;
        }
        let edit_restart = self.edit_restart_frames > 0;
        self.edit_restart_frames = self.edit_restart_frames.saturating_sub(1);
        self.frame = self.frame.wrapping_add(1);
        let seed_offset = self.seed.wrapping_mul(SEED_FRAMES);
        let plan = GiPlan {
            restart,
            edit_restart,
            iterations,
            frame: self.frame.wrapping_add(seed_offset),
            update_run: self.update_run.wrapping_add(seed_offset),
        };
        self.update_run = self.update_run.wrapping_add(iterations);
        plan
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events(settings: &RenderSettings) -> FrameEvents {
        FrameEvents {
            lighting: LightingKey::of(settings),
            lights_changed: false,
            objects_came_or_went: false,
            edited: false,
            warm_up: true,
        }
    }

    /// A schedule past its first frame and its warm-up.
    fn settled(settings: &RenderSettings) -> GiSchedule {
        let mut schedule = GiSchedule::default();
        for _ in 0..WARM_UP_FRAMES {
            schedule.plan(events(settings));
        }
        schedule
    }

    #[test]
    fn the_first_frame_restarts_and_a_fresh_cache_warms_up_then_settles() {
        let settings = RenderSettings::default();
        let mut schedule = GiSchedule::default();
        let first = schedule.plan(events(&settings));
        assert!(first.restart, "no light was seen before");
        assert_eq!((first.iterations, first.frame, first.update_run), (RESTART_ITERATIONS, FIRST_FRAME + 1, 0));
        let second = schedule.plan(events(&settings));
        assert!(!second.restart);
        assert_eq!((second.iterations, second.update_run), (WARM_UP_ITERATIONS, RESTART_ITERATIONS));
        for _ in 2..WARM_UP_FRAMES {
            assert_eq!(schedule.plan(events(&settings)).iterations, WARM_UP_ITERATIONS);
        }
        assert_eq!(schedule.plan(events(&settings)).iterations, 1, "warm-up over");
        assert_eq!(schedule.restarts(), 1);
    }

    #[test]
    fn without_the_warm_up_a_fresh_cache_runs_one_iteration() {
        let settings = RenderSettings::default();
        let mut schedule = GiSchedule::default();
        schedule.plan(events(&settings));
        assert_eq!(schedule.plan(FrameEvents { warm_up: false, ..events(&settings) }).iterations, 1);
    }

    #[test]
    fn every_change_of_light_restarts_the_entries() {
        let settings = RenderSettings::default();
        let changed = |f: fn(&mut RenderSettings)| {
            let mut s = settings.clone();
            f(&mut s);
            LightingKey::of(&s)
        };
        let keys = [
            changed(|s| s.lighting = Lighting::Emitters),
            changed(|s| s.time += 1.0),
            changed(|s| s.sun = !s.sun),
            changed(|s| s.shadows = !s.shadows),
        ];
        for key in keys {
            assert_ne!(key, LightingKey::of(&settings));
            let mut schedule = settled(&settings);
            let plan = schedule.plan(FrameEvents { lighting: key, ..events(&settings) });
            assert_eq!((plan.restart, plan.iterations), (true, RESTART_ITERATIONS));
        }
        for event in [
            FrameEvents { lights_changed: true, ..events(&settings) },
            FrameEvents { objects_came_or_went: true, ..events(&settings) },
        ] {
            assert!(settled(&settings).plan(event).restart);
        }
        assert!(!settled(&settings).plan(events(&settings)).restart, "nothing changed");
    }

    #[test]
    fn an_edit_restarts_the_blends_it_reached_for_a_few_frames() {
        let settings = RenderSettings::default();
        let mut schedule = settled(&settings);
        assert!(!schedule.plan(events(&settings)).edit_restart);
        assert!(schedule.plan(FrameEvents { edited: true, ..events(&settings) }).edit_restart);
        for _ in 1..EDIT_RESTART_FRAMES {
            assert!(schedule.plan(events(&settings)).edit_restart);
        }
        assert!(!schedule.plan(events(&settings)).edit_restart);
    }

    #[test]
    fn settled_entries_skip_frames_only_while_the_light_is_old() {
        let settings = RenderSettings::default();
        let mut schedule = GiSchedule::default();
        assert_eq!(schedule.plan(events(&settings)).settled_period(4), 1, "the first frame restarts");
        assert_eq!(schedule.plan(events(&settings)).settled_period(4), 1, "warming up");
        let mut schedule = settled(&settings);
        assert_eq!(schedule.plan(events(&settings)).settled_period(4), 4);
        assert_eq!(schedule.plan(events(&settings)).settled_period(0), 1, "a period of 0 is every frame");
        let edited = schedule.plan(FrameEvents { edited: true, ..events(&settings) });
        assert_eq!(edited.settled_period(4), 1, "an edit's light reaches every entry at once");
        for _ in 1..EDIT_RESTART_FRAMES {
            assert_eq!(schedule.plan(events(&settings)).settled_period(4), 1);
        }
        assert_eq!(schedule.plan(events(&settings)).settled_period(4), 4);
        let lamp = schedule.plan(FrameEvents { lights_changed: true, ..events(&settings) });
        assert_eq!(lamp.settled_period(4), 1);
    }

    #[test]
    fn frames_the_cache_does_not_run_in_use_up_nothing_and_lose_nothing() {
        let settings = RenderSettings::default();
        let mut schedule = GiSchedule::default();
        for _ in 0..3 * WARM_UP_FRAMES {
            schedule.hold(events(&settings));
        }
        let first = schedule.plan(events(&settings));
        assert_eq!((first.restart, first.iterations, first.frame), (true, RESTART_ITERATIONS, FIRST_FRAME + 1));
        for _ in 1..WARM_UP_FRAMES {
            assert_eq!(schedule.plan(events(&settings)).iterations, WARM_UP_ITERATIONS, "the warm-up is whole");
        }
        let mut schedule = settled(&settings);
        schedule.hold(FrameEvents { lights_changed: true, ..events(&settings) });
        schedule.hold(FrameEvents { edited: true, ..events(&settings) });
        let next = schedule.plan(events(&settings));
        assert!(next.restart && next.edit_restart, "a held frame's lamp and edit reach the next one: {next:?}");
        assert!(!schedule.plan(events(&settings)).restart, "and only it");
    }

    #[test]
    fn the_seed_offsets_the_frame_and_the_update_run() {
        let settings = RenderSettings::default();
        let mut schedule = GiSchedule::default();
        assert!(schedule.seed_changed(3));
        schedule.start_fresh(3);
        let plan = schedule.plan(events(&settings));
        assert_eq!(plan.frame, FIRST_FRAME + 1 + 3 * SEED_FRAMES);
        assert_eq!(plan.update_run, 3 * SEED_FRAMES);
        assert!(!schedule.seed_changed(3));
    }
}
