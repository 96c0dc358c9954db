//! Importing scenes nobody here built: the thesis' `.vx` files give exactly the counts of
//! `../shared/scenes/README.md`, `.vox` models give the sizes and voxel counts their files state (read by an
//! independent script), and truncated or corrupt files are one clear error, never a panic.

use glowbrick::lights::LightPool;
use glowbrick::world::import::vox::parse_vox;
use glowbrick::world::source::load_path;
use std::path::{Path, PathBuf};

/// A file carried in `tests/data` (copied from `../shared/scenes`, see its README).
fn shared(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(path)
}

/// The shared scenes folder next to the checkout, when there is one (larger models live only there).
fn shared_folder() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    dir.is_dir().then_some(dir)
}

#[test]
fn thesis_scenes_have_the_readme_counts() {
    let letters = load_path(&shared("thesis/letters.vx")).unwrap();
    let s = letters.summary();
    assert_eq!((s.voxels, s.emitters), (387_734, 1_249), "{s}");
    // Emitters by strength: 15: 834, 4: 266, 8: 149 (strength s is stored as s / pi).
    let mut by_strength = std::collections::BTreeMap::new();
    letters.grid.for_each_solid(|_, m| {
        let material = letters.palette.get(m).unwrap();
        if material.is_emissive() {
            *by_strength.entry((material.strength * std::f32::consts::PI).round() as u32).or_insert(0) += 1;
        }
    });
    assert_eq!(by_strength.into_iter().collect::<Vec<_>>(), vec![(4, 266), (8, 149), (15, 834)]);
    assert!(letters.view(Some("letters1")).is_some() && letters.view(Some("letters2")).is_some());

    let cornell = load_path(&shared("thesis/cornellbox.vx")).unwrap();
    let s = cornell.summary();
    assert_eq!((s.voxels, s.emitters), (544_416, 131_072), "{s}");
    let pool = LightPool::from_world(&cornell);
    assert_eq!(pool.counts(), (0, 256), "the ceiling light is 256 aligned emissive bricks");
    // x 64..191 in the thesis' left-handed axes is 840..967 here (x -> 1031 - x: 1027 wide, rounded up to bricks).
    assert!(
        pool.lights().all(|(_, l)| l.min.y == 248 && (840..968).contains(&l.min.x) && (64..192).contains(&l.min.z))
    );
    assert!(cornell.view(Some("cornell1")).is_some());
}

/// A `.vx` file as the thesis writes it: header, packed positions, values (`src/world/import/vx.rs`).
fn write_vx(path: &Path, size: [u32; 3], voxels: &[([u32; 3], u16)]) {
    use std::io::Write;
    let mut raw = Vec::new();
    for word in [2, 1, size[0], size[1], size[2], voxels.len() as u32] {
        raw.extend_from_slice(&word.to_le_bytes());
    }
    for ([x, y, z], _) in voxels {
        raw.extend_from_slice(&(x | y << 10 | z << 20).to_le_bytes());
    }
    for (_, value) in voxels {
        raw.extend_from_slice(&value.to_le_bytes());
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&raw).unwrap();
    std::fs::write(path, gz.finish().unwrap()).unwrap();
}

/// The thesis repository also exports scenes of other sizes (260x132x292): they mirror about their own width
/// rounded up to whole bricks, not about 1024.
#[test]
fn a_vx_export_of_another_size_mirrors_about_its_own_width() {
    let dir = std::env::temp_dir().join(format!("glowbrick-vx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("small.vx");
    let white = 0x0fff; // r = g = b = 15, strength 0
    let lamp = 0xf0f0; // green, strength 15
    write_vx(&path, [260, 132, 292], &[([0, 0, 0], white), ([259, 131, 291], lamp), ([8, 1, 2], white)]);
    let world = load_path(&path).unwrap();
    // 260 rounds up to 264 (33 bricks): x -> 263 - x.
    assert_eq!(world.grid.size().to_array(), [264, 132, 292]);
    let solid = |x, y, z| world.grid.get(bevy::math::IVec3::new(x, y, z)) != 0;
    assert!(solid(263, 0, 0) && solid(4, 131, 291) && solid(255, 1, 2));
    assert_eq!(world.summary().voxels, 3);
    assert_eq!(world.summary().emitters, 1);
    // A position past the declared width is refused with the file's own coordinates.
    write_vx(&path, [260, 132, 292], &[([260, 0, 0], white)]);
    let err = load_path(&path).unwrap_err().to_string();
    assert!(err.contains("position (260, 0, 0) outside the 260x132x292 scene"), "{err}");
}

#[test]
fn vox_models_have_the_sizes_and_counts_their_files_state() {
    // (file, models, first model's size as stored (x, y, z; z up), total voxels).
    let expected = [
        ("corvette", 1, [237, 38, 50], 129_220),
        ("deer", 4, [26, 9, 27], 1_415),
        ("monolith", 1, [24, 32, 120], 92_160),
        ("pillar", 1, [100, 100, 100], 12_354),
        ("rock", 32, [48, 48, 48], 89_451),
        ("ship", 1, [20, 20, 20], 410),
        ("teapot", 1, [126, 80, 61], 28_411),
    ];
    let mut tested = 0;
    for (name, models, size, voxels) in expected {
        let carried = shared(&format!("vox/{name}.vox"));
        let path = match (carried.is_file(), shared_folder()) {
            (true, _) => carried,
            (false, Some(dir)) => dir.join(format!("vox/{name}.vox")),
            (false, None) => continue,
        };
        tested += 1;
        let file = parse_vox(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(file.models.len(), models, "{name}");
        assert_eq!(file.models[0].size, size, "{name}");
        assert_eq!(file.models.iter().map(|m| m.voxels.len()).sum::<usize>(), voxels, "{name}");
        // In the world, z-up becomes y-up: the first model's height is its stored z.
        let world = load_path(&path).unwrap();
        assert_eq!(world.summary().voxels, voxels as u64, "{name}");
        assert!(world.grid.size().y >= size[2], "{name}");
    }
    assert!(tested >= 4, "the carried models are always tested");
}

#[test]
fn truncated_or_corrupt_files_are_one_clear_error() {
    let dir = std::env::temp_dir().join(format!("glowbrick-imports-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vx = std::fs::read(shared("thesis/letters.vx")).unwrap();
    let vox = std::fs::read(shared("vox/ship.vox")).unwrap();
    let mut cases: Vec<(String, Vec<u8>)> = vec![
        ("empty.vx".into(), Vec::new()),
        ("cut-header.vx".into(), vx[..20].to_vec()),
        ("cut-middle.vx".into(), vx[..vx.len() / 3].to_vec()),
        ("not-gzip.vx".into(), b"this is not a gzip stream at all".to_vec()),
        ("not-vox.vox".into(), b"RIFF....".to_vec()),
    ];
    // Cuts through a small .vox file (a cut exactly between two chunks would leave a smaller valid file; none of
    // these offsets is one).
    for cut in (0..vox.len()).step_by(97) {
        cases.push((format!("cut-{cut}.vox"), vox[..cut].to_vec()));
    }
    // A chunk whose declared size runs past the end of the file (bytes 24..28: the first child chunk's size).
    let mut bad = vox.clone();
    bad[24..28].copy_from_slice(&u32::MAX.to_le_bytes());
    cases.push(("huge-chunk.vox".into(), bad));
    // A voxel outside its model's size.
    let mut outside = vox.clone();
    let xyzi = outside.windows(4).position(|w| w == b"XYZI").unwrap();
    outside[xyzi + 16] = 250;
    cases.push(("voxel-outside.vox".into(), outside));
    for (name, bytes) in cases {
        let path = dir.join(&name);
        std::fs::write(&path, &bytes).unwrap();
        let err = load_path(&path).expect_err(&name).to_string();
        assert!(err.starts_with(&path.display().to_string()) && !err.contains('\n'), "{name}: {err}");
    }
}

#[test]
fn a_magicavoxel_scene_imports_as_laid_out_with_its_emissive_material() {
    use bevy::math::IVec3;
    use glowbrick::world::import::vox::{EMIT_STRENGTH, vox_world};
    let file = parse_vox(&crate::vox_scene::scene_graph_vox()).unwrap();
    assert_eq!(file.models.len(), 2);
    assert_eq!(file.placed.len(), 2, "both shapes are placed: {:?}", file.placed);
    assert_eq!(file.emissive, vec![(2, 2.0 * EMIT_STRENGTH)]);
    let world = vox_world(&file).unwrap();
    // MagicaVoxel z-up: the slab lies at our y = 0, 6 x 6 in x and z; the cube's corner is at MagicaVoxel
    // (2, 2, 4), ours (2, 4, 2), 2 voxels on a side.
    assert_eq!(world.grid.size().to_array(), [6, 6, 6]);
    for (p, solid) in [
        (IVec3::new(0, 0, 0), true),
        (IVec3::new(5, 0, 5), true),
        (IVec3::new(2, 4, 2), true),
        (IVec3::new(3, 5, 3), true),
        (IVec3::new(2, 3, 2), false),
        (IVec3::new(4, 4, 4), false),
    ] {
        assert_eq!(world.grid.get(p) != 0, solid, "{p}");
    }
    let lamp = world.palette.get(world.grid.get(IVec3::new(2, 4, 2))).unwrap().clone();
    assert!(lamp.is_emissive() && lamp.strength == 2.0 * EMIT_STRENGTH, "{lamp:?}");
    assert!(!world.palette.get(world.grid.get(IVec3::ZERO)).unwrap().is_emissive());
    let s = world.summary();
    assert_eq!((s.voxels, s.emitters), (44, 8), "{s}");
    assert_eq!(LightPool::from_world(&world).len() as u64, s.voxel_lights + s.brick_lights);
    assert!(s.voxel_lights + s.brick_lights > 0, "the lamp joins the light pool: {s}");
}

#[test]
fn a_hostile_scene_graph_is_one_error_line() {
    // Fuzz finding (seed 7, 1,000,000 inputs): a translation holding a line break was quoted raw.
    let good = crate::vox_scene::scene_graph_vox();
    let at = good.windows(5).position(|w| w == b"3 3 5").unwrap();
    let mut bad = good.clone();
    bad[at..at + 5].copy_from_slice(b"3 3\n\x04");
    let e = parse_vox(&bad).unwrap_err();
    assert!(e.contains("translation '3 3\\n\\u{4}' is not three integers") && !e.contains('\n'), "{e}");
    // A shape naming a model the file does not hold.
    let shape = good.windows(4).rposition(|w| w == b"nSHP").unwrap();
    let mut missing = good.clone();
    // The model id is the last word before the shape's empty model dictionary: id, dict(0), count 1, model, dict(0).
    missing[shape + 12 + 4 + 4 + 4..shape + 12 + 4 + 4 + 8].copy_from_slice(&9i32.to_le_bytes());
    let e = parse_vox(&missing).unwrap_err();
    assert!(e.contains("a shape names model 9; the file holds 2"), "{e}");
}
