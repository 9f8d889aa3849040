//! The demo's overlay panel (feature `overlay`) laid out without a window
//! (`caustics::app::panel_rect`): with every section shown it stays inside
//! a 640x480 window, scrolling rather than running off the bottom.
#![cfg(feature = "overlay")]

use caustics::app::{panel_rect, CompareStatus, MediumValues, UiData, View};
use caustics::params::Params;
use caustics::techniques::TECHNIQUES;
use caustics::vk::PassTiming;

/// Every section the panel can show: the technique with the most
/// parameters, a medium, three lights, an environment, a snapshot with its
/// FLIP, 16 timed passes (beams, 24 parameters). Without the window's
/// vertical scrolling it ended at y = 1371 on this screen.
#[test]
fn panel_fits_a_480_pixel_window() {
    let info = TECHNIQUES.iter().max_by_key(|t| t.params().len()).unwrap();
    let params = Params::resolve(info.name, info.params(), &[]).unwrap();
    let timings: Vec<PassTiming> = (0..16)
        .map(|i| PassTiming {
            name: format!("pass {i}"),
            ms: 1.0,
        })
        .collect();
    let history = vec![16.0f32; 120];
    let data = UiData {
        technique: info.name,
        params: &params,
        timings: &timings,
        history_ms: &history,
        components: info.components,
        component_mask: u32::MAX,
        medium: Some(MediumValues {
            sigma_s: [0.1; 3],
            sigma_a: [0.01; 3],
            g: 0.5,
        }),
        light_intensities: vec![[1.0; 3]; 3],
        environment_rotate: Some(0.0),
        compare: CompareStatus {
            view: View::Live,
            passes: Some(3),
            photons: 1 << 20,
            flip_mean: Some(0.1),
            size: (640, 480),
            component: "all",
            image: None,
        },
    };
    let [left, top, right, bottom] = panel_rect(&data, 640.0, 480.0);
    println!(
        "{} ({} parameters): panel [{left}, {top}] - [{right}, {bottom}]",
        info.name,
        info.params().len()
    );
    assert!(top >= 0.0 && left >= 0.0 && right <= 640.5);
    assert!(
        bottom <= 480.5,
        "the panel ends at y = {bottom} on a 480-point screen"
    );
    // With room for all of it, all of it shows: no scrolling on a tall screen.
    let [.., tall_bottom] = panel_rect(&data, 640.0, 1600.0);
    println!("on a 1600-point screen the panel ends at y = {tall_bottom}");
    assert!(
        tall_bottom >= 1300.0,
        "the panel ends at y = {tall_bottom} on a 1600-point screen"
    );
}
