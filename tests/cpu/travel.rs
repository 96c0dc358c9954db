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
    // The first window was whole (17 x 17); what fell behind went (at most a region of slack each side: 19 x 19).
    assert!(report.resident_max >= 17 * 17, "{} resident at the most", report.resident_max);
    assert!(report.resident_max <= 19 * 19, "{} resident at the most", report.resident_max);
    assert!(report.ticks >= 300, "{} ticks of a 6.7 s flight at 60 a second", report.ticks);
    let text = travel_markdown(&config, &report);
    assert!(text.contains("| ticks with a region in view reach missing |"), "{text}");
}
