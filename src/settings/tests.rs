//! The settings table against the messages, spellings and ranges the command line had before it.

use super::*;

/// What `--set` accepts, split into the values to try: every name, or both ends of a range.
fn valid_values(setting: &Setting) -> Vec<String> {
    let accepts = setting.accepts();
    accepts
        .split('|')
        .flat_map(|part| match part.strip_prefix('<').and_then(|r| r.strip_suffix('>')) {
            Some(range) => range.split("..").map(String::from).collect(),
            None => vec![part.to_string()],
        })
        .collect()
}

#[test]
fn the_messages_list_the_keys_and_values_as_before_the_table() {
    // As before the table, with the game's lighting (`full`, `emitters`), the time of day and frame pacing added.
    assert_eq!(
        valid_pairs(),
        "lighting=full|emitters|nee|sun, pick=power|uniform, accumulate=on|off, \
         debug=none|albedo|normal|hit|depth|reservoir|variance|history|indirect, sun=on|off, time=<0..24>, \
         shadows=on|off, exposure=<0.001..1000>, seed=<0..1000>, traversal=auto|dda|occupancy, pacing=on|off, denoise=on|off, \
         render_scale=auto|<0.25..1>, frame_target=<1..10000>, \
         candidates=<1..64>, taps=<0..16>, radius=<0..100>, temporal=on|off, spatial=on|off, \
         sample=area|point, reuse=biased|one-ray|unbiased, local_lights=on|off, initial_visibility=on|off, light_tiles=on|off, gi=on|off, gi_cached_rays=<4..128>, gi_update=<1..64>, \
         gi_period=<1..8>, gi_alpha=<0.001..1>, gi_table=<4096..4194304>, gi_cell=<1..16>, gi_filter=on|off, gi_bounces=on|off, gi_cached_hits=on|off, gi_qmc=on|off, gi_reservoirs=on|off, gi_guiding=on|off, gi_warm_up=on|off"
    );
}

#[test]
fn every_value_a_key_advertises_round_trips() {
    for setting in SETTINGS {
        assert_eq!(SETTINGS.iter().filter(|s| s.key == setting.key).count(), 1, "{} twice", setting.key);
        let values = valid_values(setting);
        assert!(values.len() >= 2, "{}", setting.key);
        for value in values {
            let mut s = RenderSettings::default();
            s.set(&format!("{}={value}", setting.key)).unwrap();
            assert_eq!(setting.get(&s), value, "{}", setting.key);
            // Setting what get reads back changes nothing.
            let read = s.clone();
            s.set(&format!("{}={}", setting.key, setting.get(&read))).unwrap();
            assert_eq!(s, read, "{}", setting.key);
        }
        let mut s = RenderSettings::default();
        s.set(&format!("{}={}", setting.key, setting.default_value())).unwrap();
        assert_eq!(s, RenderSettings::default(), "{}", setting.key);
    }
}

#[test]
fn switches_take_the_usual_spellings() {
    for (value, on) in [("on", true), ("true", true), ("1", true), ("off", false), ("false", false), ("0", false)] {
        let s = RenderSettings::default().with_pairs(&[format!("temporal={value}")]).unwrap();
        assert_eq!(s.restir.temporal, on, "{value}");
    }
}

#[test]
fn an_unknown_key_or_a_missing_value_lists_every_key() {
    for pair in ["colour=blue", "colour"] {
        let error = RenderSettings::default().set(pair).unwrap_err();
        for setting in SETTINGS {
            assert!(error.contains(&format!("{}={}", setting.key, setting.accepts())), "{error}");
        }
    }
    assert!(RenderSettings::default().set("colour=blue").unwrap_err().starts_with("unknown setting 'colour'"));
    assert!(RenderSettings::default().set("colour").unwrap_err().starts_with("setting 'colour' is not KEY=VALUE"));
}

#[test]
fn bad_values_are_refused_with_what_is_valid() {
    for setting in SETTINGS {
        let accepts = setting.accepts();
        let error = RenderSettings::default().set(&format!("{}=sideways", setting.key)).unwrap_err();
        if let Some(range) = accepts.strip_prefix('<').and_then(|r| r.strip_suffix('>')) {
            assert!(error.contains(&format!("(valid: {range})")), "{error}");
            let (lo, hi) = range.split_once("..").unwrap();
            let (lo, hi): (f64, f64) = (lo.parse().unwrap(), hi.parse().unwrap());
            for outside in [lo - 1.0, hi + 1.0] {
                let error = RenderSettings::default().set(&format!("{}={outside}", setting.key)).unwrap_err();
                let expected = format!("setting {}: {outside} is out of range (valid: {range})", setting.key);
                assert_eq!(error, expected);
            }
        } else {
            assert_eq!(error, format!("setting {}: 'sideways' is not one of {accepts}", setting.key));
        }
    }
    assert_eq!(
        RenderSettings::default().set("candidates=lots").unwrap_err(),
        "setting candidates: 'lots' is not a whole number (valid: 1..64)"
    );
    assert_eq!(
        RenderSettings::default().set("radius=NaN").unwrap_err(),
        "setting radius: NaN is out of range (valid: 0..100)"
    );
    for outside in ["0.2", "1.5", "NaN", "inf", "-1"] {
        assert_eq!(
            RenderSettings::default().set(&format!("render_scale={outside}")).unwrap_err(),
            format!("setting render_scale: {outside} is out of range (valid: auto|<0.25..1>)")
        );
    }
}

/// `render_scale` is `auto` or a number in its range; the panel steps through auto and the listed scales.
#[test]
fn the_render_scale_is_auto_or_a_scale_and_the_panel_steps_through_both() {
    let mut s = RenderSettings::default();
    assert_eq!(s.render_scale, RenderScale::Fixed(1.0));
    assert_eq!(RenderSettings::game().render_scale, RenderScale::Auto);
    s.set("render_scale=0.5").unwrap();
    assert_eq!(s.render_scale, RenderScale::Fixed(0.5));
    let render_scale = setting("render_scale").unwrap();
    let mut shown = Vec::new();
    for _ in 0..6 {
        render_scale.step(&mut s, 1);
        shown.push(render_scale.get(&s));
    }
    assert_eq!(shown, ["0.33", "0.25", "auto", "1", "0.75", "0.5"]);
    render_scale.step(&mut s, -1);
    assert_eq!(render_scale.get(&s), "0.75");
    s.set("render_scale=0.6").unwrap();
    render_scale.step(&mut s, 1);
    assert_eq!(render_scale.get(&s), "0.5", "from between two listed scales to the smaller one");
    s.set("render_scale=0.6").unwrap();
    render_scale.step(&mut s, -1);
    assert_eq!(render_scale.get(&s), "0.75", "and to the larger one");
    let from_ron =
        RenderSettings::default().with_ron(r#"{"render_scale": 0.5, "frame_target": 33.3}"#, "t.ron").unwrap();
    assert_eq!((from_ron.render_scale, from_ron.frame_target), (RenderScale::Fixed(0.5), 33.3));
    let auto = RenderSettings::default().with_ron(r#"{"render_scale": "auto"}"#, "t.ron").unwrap();
    assert_eq!(auto.render_scale, RenderScale::Auto);
}

#[test]
fn panel_steps_stay_within_what_set_accepts() {
    for setting in SETTINGS {
        for direction in [1, -1] {
            let mut s = RenderSettings::default();
            for _ in 0..40 {
                setting.step(&mut s, direction);
                let value = setting.get(&s);
                RenderSettings::default().set(&format!("{}={value}", setting.key)).unwrap();
            }
        }
    }
    // Choices cycle; numbers stop at the ends.
    let lighting = setting("lighting").unwrap();
    let mut s = RenderSettings::default();
    let mut cycle = vec![];
    for _ in 0..3 {
        lighting.step(&mut s, 1);
        cycle.push(lighting.get(&s));
    }
    assert_eq!(cycle, ["emitters", "nee", "sun"]);
    lighting.step(&mut s, -1);
    assert_eq!(s.lighting, Lighting::Nee);
    let mut s = RenderSettings::default();
    (0..20).for_each(|_| setting("gi_cached_rays").unwrap().step(&mut s, 1));
    assert_eq!(s.gi.rays, GI_RAYS_RANGE.1);
}

#[test]
fn help_text_gives_every_key_its_values_and_default() {
    let help = help_text();
    for setting in SETTINGS {
        let line = format!("  {}={}  [default: {}]", setting.key, setting.accepts(), setting.default_value());
        assert!(help.contains(&line), "{line}\n{help}");
    }
    assert!(help.contains("  candidates=<1..64>  [default: 32]") && help.contains("  lighting=full|emitters|nee|sun"));
}

#[test]
fn the_summary_shows_the_sections_that_apply() {
    let s = RenderSettings::default();
    // The default, lighting=full, samples its emitters by ReSTIR: those settings apply.
    assert_eq!(s.summary().lines().count(), 2);
    assert!(s.summary().starts_with("lighting=full pick=power"), "{}", s.summary());
    let sun_only = s.clone().with_pairs(&["lighting=sun".to_string()]).unwrap();
    assert_eq!(sun_only.summary().lines().count(), 1);
    let s = s.with_pairs(&["lighting=restir".to_string(), "gi=on".to_string(), "sample=point".to_string()]);
    let summary = s.unwrap().summary();
    assert_eq!(summary.lines().count(), 3, "{summary}");
    assert!(
        summary.contains(
            "candidates=32 taps=1 radius=30 temporal=on spatial=on sample=point reuse=one-ray local_lights=on"
        )
    );
    assert!(
        summary
            .contains("gi_cached_rays=64 gi_update=8 gi_period=1 gi_alpha=0.03 gi_table=262144 gi_cell=4 gi_filter=on"),
        "{summary}"
    );
}

#[test]
fn a_ron_settings_file_sets_what_set_sets_and_rejects_the_same() {
    let text = r#"{"lighting": "restir", "candidates": 16, "temporal": false, "radius": 12.5, "sample": "point"}"#;
    let s = RenderSettings::default().with_ron(text, "t.ron").unwrap();
    // `restir` is read as `emitters`, the name it had before the sun and sky joined ReSTIR.
    assert_eq!(s.lighting, Lighting::Emitters);
    assert_eq!(setting("lighting").unwrap().get(&s), "emitters");
    assert_eq!((s.restir.candidates, s.restir.temporal, s.restir.radius), (16, false, 12.5));
    assert_eq!(s.restir.sample, LightSample::Point);
    let bad = RenderSettings::default().with_ron(r#"{"candidates": 0}"#, "t.ron").unwrap_err();
    assert!(bad.contains("t.ron: setting candidates: 0 is out of range (valid: 1..64)"), "{bad}");
    let broken = RenderSettings::default().with_ron("{\"lighting\": ", "t.ron").unwrap_err();
    assert!(broken.starts_with("t.ron:1:"), "{broken}");
    let nested = RenderSettings::default().with_ron(r#"{"lighting": ["restir"]}"#, "t.ron").unwrap_err();
    assert!(nested.contains("is not a string, number or bool"), "{nested}");
}

/// Found by the fuzzer (`stress --fuzz`, settings input 378 of seed 1): a settings file whose key or value
/// string spans lines printed an error of several lines.
#[test]
fn an_error_quoting_a_newline_from_a_settings_file_stays_one_line() {
    let file = "{\"temporal\nspatial\": \"on\", \"accumulate\": \"of\nf\"}";
    let error = RenderSettings::default().with_ron(file, "t.ron").unwrap_err();
    assert!(!error.contains('\n') && error.contains("\\n"), "{error}");
    let error = RenderSettings::default().set("accumulate=o\nn").unwrap_err();
    assert!(!error.contains('\n'), "{error}");
}

/// Found by the fuzzer (`stress --fuzz 5000000 --seed 2`, settings input 120745): a key spanning lines whose
/// value is not a string, number or bool printed an error of two lines.
#[test]
fn an_error_about_a_value_of_the_wrong_kind_stays_one_line() {
    let error = RenderSettings::default().with_ron("{\"temp\noral\": ()}", "t.ron").unwrap_err();
    assert!(!error.contains('\n') && error.contains("is not a string, number or bool"), "{error}");
}

/// Renamed keys are still read from old settings files and scripts, into the setting that replaced them.
#[test]
fn renamed_keys_still_set_their_settings() {
    let old = RenderSettings::default().with_pairs(&["gi_cache=on".to_string(), "gi_rays=16".to_string()]).unwrap();
    let new = RenderSettings::default()
        .with_pairs(&["gi_cached_hits=on".to_string(), "gi_cached_rays=16".to_string()])
        .unwrap();
    assert_eq!((old.gi.cache, old.gi.rays), (true, 16));
    assert_eq!(old, new);
}

/// `traversal=auto`, the default, is the DDA on a CPU adapter (lavapipe) and the occupancy walk on a GPU; a walk
/// named outright is that walk on either.
#[test]
fn auto_traversal_is_the_dda_on_a_cpu_adapter_and_the_masks_on_a_gpu() {
    assert_eq!(RenderSettings::default().traversal, Traversal::Auto);
    assert_eq!(Traversal::Auto.resolve(true), Traversal::Dda);
    assert_eq!(Traversal::Auto.resolve(false), Traversal::Occupancy);
    for cpu in [true, false] {
        assert_eq!(Traversal::Dda.resolve(cpu), Traversal::Dda);
        assert_eq!(Traversal::Occupancy.resolve(cpu), Traversal::Occupancy);
    }
}
