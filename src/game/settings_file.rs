//! The player's settings file: what the F4 panel, L, G and N changed, kept for the next `play`. It lives beside
//! the saves (`saves/settings.ron` by default: the directory of `--save`), holds the panel's rows but the time of
//! day (the world's own) and the GI switch, and is written atomically when one of them changes. `play` applies it
//! over the game's defaults, under `--config` and `--set`, so a command line still wins for that session.

use super::settings_panel::ROWS;
use crate::settings::{RenderSettings, setting};
use crate::world::format::write_atomically;
use bevy::prelude::*;
use std::path::{Path, PathBuf};

/// The file's name in the saves' directory.
pub const FILE_NAME: &str = "settings.ron";

/// Where this game's settings file is (a resource: set by `run_game`, absent in apps that keep no file).
#[derive(Resource, Clone, Debug)]
pub struct SettingsFile(pub PathBuf);

/// The settings file beside `save` (the world's save path).
pub fn beside(save: &Path) -> PathBuf {
    save.parent().unwrap_or(Path::new("")).join(FILE_NAME)
}

/// The keys the file keeps: the panel's rows but `time` (a world's time of day is saved with the world), and the
/// GI cache's switch (G).
pub fn kept_keys() -> impl Iterator<Item = &'static str> {
    ROWS.into_iter().filter(|key| *key != "time").chain(["gi"])
}

/// The file's text: a RON map of `--set` keys to their values, as `--config` reads.
pub fn to_ron(settings: &RenderSettings) -> String {
    let pairs: Vec<String> =
        kept_keys().filter_map(|key| setting(key).map(|s| format!("    {key:?}: {:?},", s.get(settings)))).collect();
    format!("{{\n{}\n}}\n", pairs.join("\n"))
}

/// `base` with the file at `path` applied, or `base` where there is no file. A file that cannot be read or
/// parsed is an error naming it (never silently replaced: the player may want what is in it).
pub fn load_over(base: RenderSettings, path: &Path) -> Result<RenderSettings, String> {
    match std::fs::read_to_string(path) {
        Ok(text) => base
            .with_ron(&text, &path.display().to_string())
            .map_err(|e| format!("{e} (the game's settings file: fix it, or delete it to start from the defaults)")),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(base),
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// Writes `settings` to the file.
pub fn write(settings: &RenderSettings, path: &Path) -> std::io::Result<()> {
    write_atomically(path, to_ron(settings).as_bytes())
}

/// Writes the file when a kept setting changed since the last write (the panel's keys, L, or a key of the game
/// such as G or N that changes a panel row).
pub fn keep_settings(
    settings: Res<RenderSettings>,
    file: Option<Res<SettingsFile>>,
    mut written: Local<Option<String>>,
) {
    let Some(file) = file else {
        return;
    };
    if !settings.is_changed() {
        return;
    }
    let text = to_ron(&settings);
    // The first look is what the game started with (already on disk, or the defaults): nothing to write.
    if written.as_ref().is_some_and(|last| *last != text)
        && let Err(e) = write_atomically(&file.0, text.as_bytes())
    {
        warn!("could not keep the settings in {}: {e}", file.0.display());
    }
    *written = Some(text);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::RenderScale;

    /// What the file holds reads back to the same settings: every kept row, `auto` and fixed scales alike.
    #[test]
    fn the_file_reads_back_to_the_same_settings() {
        let mut settings = RenderSettings::game();
        settings.set("candidates=12").unwrap();
        settings.set("render_scale=0.5").unwrap();
        settings.set("frame_target=33.3").unwrap();
        settings.set("denoise=off").unwrap();
        settings.set("gi=off").unwrap();
        let read = load_over(RenderSettings::game(), &write_to_temp(&settings, "round")).unwrap();
        for key in kept_keys() {
            let s = setting(key).unwrap();
            assert_eq!(s.get(&read), s.get(&settings), "{key}");
        }
        assert_eq!(read.render_scale, RenderScale::Fixed(0.5));
        let auto = load_over(RenderSettings::default(), &write_to_temp(&RenderSettings::game(), "auto")).unwrap();
        assert_eq!(auto.render_scale, RenderScale::Auto);
    }

    /// The time of day is the world's: the file neither holds nor changes it.
    #[test]
    fn the_time_of_day_is_not_kept() {
        let mut settings = RenderSettings::game();
        settings.set("time=21").unwrap();
        assert!(!to_ron(&settings).contains("\"time\""));
        let mut base = RenderSettings::game();
        base.set("time=9").unwrap();
        assert_eq!(load_over(base, &write_to_temp(&settings, "time")).unwrap().time, 9.0);
    }

    /// No file: the defaults. A broken file: one error naming it, and the file left as it was.
    #[test]
    fn a_missing_file_gives_the_defaults_and_a_broken_one_an_error() {
        let dir = std::env::temp_dir().join(format!("glowbrick-settings-file-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let missing = dir.join("none.ron");
        assert_eq!(load_over(RenderSettings::game(), &missing).unwrap(), RenderSettings::game());
        let broken = dir.join("broken.ron");
        std::fs::write(&broken, "{\"candidates\": \"many\"").unwrap();
        let error = load_over(RenderSettings::game(), &broken).unwrap_err();
        assert!(error.contains("broken.ron") && error.contains("settings file"), "{error}");
        let out_of_range = dir.join("range.ron");
        std::fs::write(&out_of_range, "{\"render_scale\": \"7\"}").unwrap();
        assert!(load_over(RenderSettings::game(), &out_of_range).is_err());
        assert_eq!(std::fs::read_to_string(&broken).unwrap(), "{\"candidates\": \"many\"");
    }

    #[test]
    fn the_file_lies_beside_the_save() {
        assert_eq!(beside(Path::new("saves/world.ron")), Path::new("saves/settings.ron"));
        assert_eq!(beside(Path::new("world.ron")), Path::new("settings.ron"));
    }

    fn write_to_temp(settings: &RenderSettings, name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("glowbrick-settings-file-{}", std::process::id()));
        let path = dir.join(format!("{name}.ron"));
        write(settings, &path).unwrap();
        path
    }
}
