//! An endless world on disk: a folder holding `world.ron` (the format tag and version, the seed and the height)
//! and `regions/r.X.Z.ron`, one file per region kept, each an ordinary world file of one region (64 x height x
//! 64 voxels, the generator's palette), so the world files' parser, its limits and its fuzzer cover them too.
//! Regions without a file are the generator's. Every file is written atomically, a region's previous file
//! kept as `.bak`. `world.ron` also holds where the player stood (a region key and a view from its corner, so a
//! position a million voxels out is saved as exactly as one at the origin) and the time of day.

use super::format::{LoadError, load_world, one_line, read_limited, save_with_backup, write_atomically};
use super::generate::endless::REGION_EDGE;
use super::objects::{MAX_SAVED_OBJECTS, SavedObject};
use super::palette::Palette;
use super::{CameraView, VoxelWorld};
use bevy::math::{IVec2, UVec3, Vec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub const ENDLESS_TAG: &str = "glowbrick-endless-world";
pub const ENDLESS_VERSION: u32 = 1;
/// `world.ron` is a few lines; anything larger is not one.
const MAX_WORLD_FILE_BYTES: u64 = 64 * 1024;

/// `world.ron`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct EndlessWorldFile {
    format: String,
    version: u32,
    seed: u32,
    height: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    player: Option<SavedPlayer>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    time_of_day: Option<f32>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    objects: Vec<SavedObjectAt>,
}

/// A moving object, its anchor relative to a region's corner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SavedObjectAt {
    region: (i32, i32),
    object: SavedObject,
}

/// Where the player stood: a region and a view whose origin is relative to the region's corner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SavedPlayer {
    region: (i32, i32),
    view: CameraView,
}

/// How far (voxels, x and z) from its region's corner a saved player's view may stand.
pub const PLAYER_REACH: f32 = 4096.0;

/// An endless world's save folder.
#[derive(Clone, Debug, PartialEq)]
pub struct EndlessSave {
    pub folder: PathBuf,
    pub seed: u32,
    pub height: u32,
    /// Where the player stood when last saved: a region key and a view from that region's corner.
    pub player: Option<(IVec2, CameraView)>,
    pub time_of_day: Option<f32>,
    /// The moving objects: a region key each and the object, its anchor from that region's corner.
    pub objects: Vec<(IVec2, SavedObject)>,
}

impl EndlessSave {
    /// Opens the save in `folder`, or starts one there for `seed` and `height` when it holds none. A folder that
    /// holds another seed's world is refused: its regions would not join this one's.
    pub fn open_or_create(folder: &Path, seed: u32, height: u32) -> Result<Self, String> {
        if folder.join("world.ron").exists() {
            let save = Self::open(folder).map_err(|e| e.to_string())?;
            if (save.seed, save.height) != (seed, height) {
                return Err(format!(
                    "{} holds the endless world of seed {} and height {}, not seed {seed} and height {height}",
                    folder.display(),
                    save.seed,
                    save.height
                ));
            }
            return Ok(save);
        }
        std::fs::create_dir_all(folder.join("regions")).map_err(|e| format!("{}: {e}", folder.display()))?;
        let save = EndlessSave {
            folder: folder.to_path_buf(),
            seed,
            height,
            player: None,
            time_of_day: None,
            objects: Vec::new(),
        };
        save.write_world_file()?;
        Ok(save)
    }

    /// Writes `world.ron` (atomically, the previous one kept as `.bak`).
    pub fn write_world_file(&self) -> Result<(), String> {
        let file = EndlessWorldFile {
            format: ENDLESS_TAG.into(),
            version: ENDLESS_VERSION,
            seed: self.seed,
            height: self.height,
            player: self.player.clone().map(|(key, view)| SavedPlayer { region: (key.x, key.y), view }),
            time_of_day: self.time_of_day,
            objects: self
                .objects
                .iter()
                .map(|(key, object)| SavedObjectAt { region: (key.x, key.y), object: object.clone() })
                .collect(),
        };
        let text = ron::ser::to_string_pretty(&file, ron::ser::PrettyConfig::new()).map_err(|e| e.to_string())?;
        let path = self.folder.join("world.ron");
        let backup = super::format::backup_path(&path);
        if path.exists() {
            let _ = std::fs::copy(&path, &backup);
        }
        write_atomically(&path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The saved player's view in world coordinates.
    pub fn player_view(&self) -> Option<CameraView> {
        self.player.as_ref().map(|(key, view)| {
            let corner = Vec3::new((key.x * REGION_EDGE) as f32, 0.0, (key.y * REGION_EDGE) as f32);
            CameraView { origin: (corner + Vec3::from(view.origin)).into(), ..view.clone() }
        })
    }

    /// Opens the save in `folder`, validating `world.ron`.
    pub fn open(folder: &Path) -> Result<Self, LoadError> {
        let path = folder.join("world.ron");
        let text = read_limited(&path, MAX_WORLD_FILE_BYTES)?;
        Self::parse(&text, folder, &path.display().to_string())
    }

    /// The save whose `world.ron` reads `text` (`location` names it in errors), in `folder`.
    pub fn parse(text: &str, folder: &Path, location: &str) -> Result<Self, LoadError> {
        let fail = |message: String| LoadError { location: location.to_string(), message };
        let file: EndlessWorldFile = ron::from_str(text).map_err(|e| fail(one_line(&e.to_string())))?;
        if file.format != ENDLESS_TAG {
            return Err(fail(format!("not an endless world (format {:?}, expected {ENDLESS_TAG:?})", file.format)));
        }
        if file.version != ENDLESS_VERSION {
            return Err(fail(format!("version {} (this build reads {ENDLESS_VERSION})", file.version)));
        }
        if !(40..=super::grid::MAX_WORLD_EDGE).contains(&file.height) {
            return Err(fail(format!("height {} is outside 40..={}", file.height, super::grid::MAX_WORLD_EDGE)));
        }
        let keys = i32::MAX / REGION_EDGE / 2;
        let key_ok = |(x, z): (i32, i32)| x.abs() <= keys && z.abs() <= keys;
        if file.objects.len() > MAX_SAVED_OBJECTS {
            return Err(fail(format!("{} objects, the most a world holds is {MAX_SAVED_OBJECTS}", file.objects.len())));
        }
        for (i, at) in file.objects.iter().enumerate() {
            if !key_ok(at.region) {
                return Err(fail(format!("object {i}: region {:?} is past the world's end", at.region)));
            }
            check_object(&at.object, file.height).map_err(|e| fail(format!("object {i}: {e}")))?;
        }
        if let Some(player) = &file.player {
            let [x, y, z] = player.view.origin;
            let near = x.abs().max(z.abs()) <= PLAYER_REACH && y.abs() <= PLAYER_REACH;
            let key_ok = key_ok(player.region);
            if let Some(problem) = player.view.problem() {
                return Err(fail(format!("the player's {problem}")));
            }
            if !(near && key_ok) {
                return Err(fail(format!(
                    "the player stands at {:?} from region {:?}: more than {PLAYER_REACH} voxels from its corner, or a region past the world's end",
                    player.view.origin, player.region
                )));
            }
        }
        if let Some(hours) = file.time_of_day.filter(|h| !(h.is_finite() && (0.0..=24.0).contains(h))) {
            return Err(fail(format!("time of day {hours} is outside 0..=24")));
        }
        Ok(EndlessSave {
            folder: folder.to_path_buf(),
            seed: file.seed,
            height: file.height,
            player: file.player.map(|p| (IVec2::new(p.region.0, p.region.1), p.view)),
            time_of_day: file.time_of_day,
            objects: file.objects.into_iter().map(|at| (IVec2::new(at.region.0, at.region.1), at.object)).collect(),
        })
    }

    pub fn region_path(&self, key: IVec2) -> PathBuf {
        self.folder.join("regions").join(format!("r.{}.{}.ron", key.x, key.y))
    }

    fn region_size(&self) -> UVec3 {
        UVec3::new(REGION_EDGE as u32, self.height, REGION_EDGE as u32)
    }

    /// Writes region `key` (atomically, its previous file kept as `.bak`).
    pub fn save_region(&self, key: IVec2, region: &VoxelWorld) -> Result<(), String> {
        if region.grid.size() != self.region_size() {
            return Err(format!("region {key} is {}, not {}", region.grid.size(), self.region_size()));
        }
        let path = self.region_path(key);
        save_with_backup(region, &path).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Region `key` as saved, or `None` where no file holds it. A file that is not a region of this world (not a
    /// world file, another size, another palette) is one clear error naming it.
    pub fn load_region(&self, key: IVec2, palette: &Palette) -> Result<Option<VoxelWorld>, LoadError> {
        let path = self.region_path(key);
        if !path.exists() {
            return Ok(None);
        }
        let region = load_world(&path)?;
        let fail = |message: String| LoadError { location: path.display().to_string(), message };
        if region.grid.size() != self.region_size() {
            return Err(fail(format!("holds a {} world, not a region of {}", region.grid.size(), self.region_size())));
        }
        if region.palette != *palette {
            return Err(fail("its palette is not the endless world's".into()));
        }
        Ok(Some(region))
    }

    /// The keys of the regions with a file, in no particular order; files of other names are passed over.
    pub fn saved_regions(&self) -> Vec<IVec2> {
        let Ok(entries) = std::fs::read_dir(self.folder.join("regions")) else { return Vec::new() };
        entries.filter_map(|e| region_key(&e.ok()?.file_name().to_string_lossy())).collect()
    }
}

/// The first problem with a saved object anchored from a region's corner, in a world `height` voxels high.
pub fn check_object(object: &SavedObject, height: u32) -> Result<(), String> {
    object.check(Vec3::new(REGION_EDGE as f32, height as f32, REGION_EDGE as f32))
}

/// The key in a region file's name, `r.X.Z.ron`.
fn region_key(name: &str) -> Option<IVec2> {
    let mut parts = name.strip_prefix("r.")?.strip_suffix(".ron")?.split('.');
    let (x, z) = (parts.next()?.parse().ok()?, parts.next()?.parse().ok()?);
    parts.next().is_none().then_some(IVec2::new(x, z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::generate::endless::EndlessGenerator;
    use bevy::math::IVec3;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("glowbrick-regions-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn a_changed_region_is_saved_alone_and_read_back_in_place_of_the_generators() {
        let dir = scratch("round-trip");
        let generator = EndlessGenerator::new(6, 48).unwrap();
        let save = EndlessSave::open_or_create(&dir, 6, 48).unwrap();
        let key = IVec2::new(-3, 7);
        let mut region = generator.region(key);
        let lamp = region.palette.id_of("lamp-warm").unwrap();
        region.grid.set(IVec3::new(5, 40, 60), lamp).unwrap();
        save.save_region(key, &region).unwrap();
        save.save_region(key, &region).unwrap();
        assert!(crate::world::format::backup_path(&save.region_path(key)).is_file(), "the previous file kept");
        let reopened = EndlessSave::open(&dir).unwrap();
        assert_eq!(reopened, save);
        assert_eq!(reopened.saved_regions(), vec![key]);
        let back = reopened.load_region(key, generator.palette()).unwrap().expect("the saved region");
        assert_eq!(back.grid.get(IVec3::new(5, 40, 60)), lamp);
        let all = |w: &VoxelWorld| w.grid.read_box(IVec3::ZERO, w.grid.size().as_ivec3());
        assert_eq!(all(&back), all(&region));
        assert!(reopened.load_region(IVec2::new(0, 0), generator.palette()).unwrap().is_none(), "never saved");
        // A window over it takes the saved region, and the generator's beside it.
        let window = generator.window(key, 3, Some(&reopened)).unwrap();
        let at = (key - window.min / REGION_EDGE) * REGION_EDGE;
        assert_eq!(window.world.grid.get(IVec3::new(at.x + 5, 40, at.y + 60)), lamp);
        let beside = generator.region(key + IVec2::X);
        let p = IVec3::new(at.x + REGION_EDGE + 5, 20, at.y + 60);
        assert_eq!(window.world.grid.get(p), beside.grid.get(IVec3::new(5, 20, 60)));
        // The player and the time of day, a million voxels out, come back exactly.
        let mut with_player = reopened.clone();
        let view = CameraView {
            name: "player".into(),
            origin: [10.25, 80.5, 3.125],
            direction: [0.0, 0.0, 1.0],
            fov_deg: 70.0,
        };
        with_player.player = Some((IVec2::new(15_625, -3), view));
        with_player.time_of_day = Some(18.5);
        let lantern = SavedObject {
            model: "lantern".into(),
            motion: crate::world::objects::SavedMotion::Drift { radius: 5.0, period: 12.0 },
            anchor: (3.5, 70.0, 60.25),
            age: 4.0,
        };
        with_player.objects = vec![(IVec2::new(15_625, -2), lantern)];
        with_player.write_world_file().unwrap();
        let back = EndlessSave::open(&dir).unwrap();
        assert_eq!(back, with_player);
        assert_eq!(back.player_view().unwrap().origin, [1_000_010.25, 80.5, -188.875]);
        // Another seed's world in the same folder is refused.
        let other = EndlessSave::open_or_create(&dir, 7, 48).unwrap_err();
        assert!(other.contains("seed 6") && other.contains("not seed 7"), "{other}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn hostile_region_and_world_files_are_one_clear_error() {
        let dir = scratch("hostile");
        let generator = EndlessGenerator::new(6, 48).unwrap();
        let save = EndlessSave::open_or_create(&dir, 6, 48).unwrap();
        let palette = generator.palette();
        // Not a world file.
        std::fs::write(save.region_path(IVec2::ZERO), "(((((garbage").unwrap();
        let e = save.load_region(IVec2::ZERO, palette).unwrap_err();
        assert!(e.location.contains("r.0.0.ron"), "{e}");
        // A world file of the wrong size.
        let wrong = VoxelWorld::new(UVec3::new(16, 48, 16), palette.clone());
        crate::world::format::save_world(&wrong, &save.region_path(IVec2::X)).unwrap();
        let e = save.load_region(IVec2::X, palette).unwrap_err().to_string();
        assert!(e.contains("not a region of"), "{e}");
        // A region with another palette.
        let foreign = VoxelWorld::new(UVec3::new(64, 48, 64), Palette::new(vec![]));
        crate::world::format::save_world(&foreign, &save.region_path(IVec2::Y)).unwrap();
        let e = save.load_region(IVec2::Y, palette).unwrap_err().to_string();
        assert!(e.contains("palette"), "{e}");
        // Names that are not regions are passed over.
        std::fs::write(dir.join("regions").join("r.1.x.ron"), "").unwrap();
        std::fs::write(dir.join("regions").join("notes.txt"), "").unwrap();
        let mut keys = save.saved_regions();
        keys.sort_by_key(|k| (k.x, k.y));
        assert_eq!(keys, vec![IVec2::ZERO, IVec2::Y, IVec2::X]);
        // world.ron: another format, a future version, an absurd height, junk.
        for (text, expected) in [
            ("(format: \"glowbrick-world\", version: 1, seed: 1, height: 64)", "not an endless world"),
            ("(format: \"glowbrick-endless-world\", version: 9, seed: 1, height: 64)", "version 9"),
            ("(format: \"glowbrick-endless-world\", version: 1, seed: 1, height: 99999)", "height 99999"),
            ("\u{0}\u{1}junk", ""),
            (
                "(format: \"glowbrick-endless-world\", version: 1, seed: 1, height: 64, player: Some((region: (0, 0), view: (name: \"p\", origin: (1e9, 0.0, 0.0), direction: (1.0, 0.0, 0.0)))))",
                "more than 4096",
            ),
            (
                "(format: \"glowbrick-endless-world\", version: 1, seed: 1, height: 64, player: Some((region: (0, 0), view: (name: \"p\", origin: (1.0, 0.0, 0.0), direction: (0.0, 0.0, 0.0)))))",
                "direction",
            ),
            (
                "(format: \"glowbrick-endless-world\", version: 1, seed: 1, height: 64, time_of_day: Some(99.0))",
                "time of day 99",
            ),
            (
                "(format: \"glowbrick-endless-world\", version: 1, seed: 1, height: 64, objects: [(region: (0, 0), object: (model: \"dragon\", motion: Still, anchor: (1.0, 2.0, 3.0), age: 0.0))])",
                "object 0: model 'dragon'",
            ),
        ] {
            std::fs::write(dir.join("world.ron"), text).unwrap();
            let e = EndlessSave::open(&dir).unwrap_err().to_string();
            assert!(e.contains("world.ron") && e.contains(expected), "{text}: {e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
