//! `bench --travel --quick`: the endless world streamed around a short real-time flight. Timing is the bench's
//! to report (the test suite's neighbours share the cores); the test holds what must hold at any speed.

use glowbrick::bench::travel::{TravelConfig, run_travel, travel_markdown};

#[test]
fn a_quick_flight_streams_regions_in_and_drops_the_ones_behind() {
    let _alone = crate::EXCLUSIVE.lock().unwrap_or_else(|e| e.into_inner());
    let config = TravelConfig::quick();
    let report = run_travel(&config).unwrap();
    // 320 voxels diagonally crosses three to four region borders on each axis: a 17-region row and column each.
    assert!(report.regions_made >= 50, "{} regions arrived during the flight", report.regions_made);
    // The game's window (16 x 16) was made of the streamer's first regions; what fell behind went (the streamer
    // keeps 21 x 21 and at most a region of slack each side: 23 x 23).
    assert!(report.resident_max >= 16 * 16, "{} resident at the most", report.resident_max);
    assert!(report.resident_max <= 23 * 23, "{} resident at the most", report.resident_max);
    assert!(report.ticks >= 300, "{} ticks of a 6.7 s flight at 60 a second", report.ticks);
    let text = travel_markdown(&config, &report);
    assert!(text.contains("| ticks with the view reach outside the window |"), "{text}");
    assert!(text.contains("| GPU upload: most in a tick / mean a tick |"), "{text}");
}
