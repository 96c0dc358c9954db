//! CPU DDA traversal against a brute-force ray-box test of every solid voxel, on random worlds and rays.

use bevy::math::{IVec3, UVec3, Vec3};
use glowbrick::world::grid::BrickGrid;
use glowbrick::world::terrain::hash_u32;
use glowbrick::world::traversal::{Face, Ray, trace, trace_brute_force};

/// Deterministic uniform floats from a counter.
struct Rng(u32);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = hash_u32(self.0.wrapping_add(0x9E37_79B9));
        self.0 as f32 / u32::MAX as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

fn random_world(rng: &mut Rng, size: UVec3) -> BrickGrid {
    let mut grid = BrickGrid::new(size);
    let s = size.as_ivec3();
    // Scattered voxels, a few boxes (homogeneous bricks), and some empty regions.
    for _ in 0..(size.x * size.y * size.z / 10) {
        let p = IVec3::new(
            (rng.next() * s.x as f32) as i32 % s.x,
            (rng.next() * s.y as f32) as i32 % s.y,
            (rng.next() * s.z as f32) as i32 % s.z,
        );
        grid.set(p, 1 + (rng.next() * 3.0) as u16 % 3).unwrap();
    }
    for _ in 0..3 {
        let a = IVec3::new(
            (rng.next() * s.x as f32) as i32 % s.x,
            (rng.next() * s.y as f32) as i32 % s.y,
            (rng.next() * s.z as f32) as i32 % s.z,
        );
        let e =
            IVec3::new(1 + (rng.next() * 12.0) as i32, 1 + (rng.next() * 12.0) as i32, 1 + (rng.next() * 12.0) as i32);
        grid.fill_box(a, (a + e).min(s), 2).unwrap();
    }
    grid
}

#[test]
fn dda_matches_brute_force_on_random_worlds() {
    let mut rng = Rng(12345);
    let mut rays = 0;
    let mut hits = 0;
    let mut ties = 0;
    for world_index in 0..12 {
        let size =
            UVec3::new(8 + (rng.next() * 40.0) as u32, 8 + (rng.next() * 30.0) as u32, 8 + (rng.next() * 40.0) as u32);
        let grid = random_world(&mut rng, size);
        let s = size.as_vec3();
        for ray_index in 0..400 {
            // Half the rays start outside the world, half inside; some are axis-aligned.
            let origin = if ray_index % 2 == 0 {
                Vec3::new(rng.range(-20.0, s.x + 20.0), rng.range(-20.0, s.y + 20.0), rng.range(-20.0, s.z + 20.0))
            } else {
                Vec3::new(rng.range(0.0, s.x), rng.range(0.0, s.y), rng.range(0.0, s.z))
            };
            let mut dir = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            if ray_index % 10 == 0 {
                dir = Vec3::ZERO;
                dir[ray_index / 10 % 3] = if rng.next() < 0.5 { -1.0 } else { 1.0 };
            }
            let ray = Ray::new(origin, dir);
            if ray.dir == Vec3::ZERO {
                continue;
            }
            rays += 1;
            let max_distance = if ray_index % 7 == 0 { rng.range(0.0, 30.0) } else { f32::INFINITY };
            let fast = trace(&grid, &ray, max_distance);
            let slow = trace_brute_force(&grid, &ray, max_distance);
            match (fast, slow) {
                (None, None) => {}
                (Some(f), Some(b)) => {
                    hits += 1;
                    assert!(
                        (f.distance - b.distance).abs() <= 1e-3,
                        "world {world_index} ray {ray_index}: distance {} vs {}",
                        f.distance,
                        b.distance
                    );
                    if f.voxel != b.voxel || f.face != b.face {
                        // Only a ray through an edge or corner may disagree, and then both voxels are entered at
                        // the same distance.
                        ties += 1;
                        assert!(
                            (f.distance - b.distance).abs() <= 1e-4,
                            "world {world_index} ray {ray_index}: {f:?} vs {b:?}"
                        );
                    }
                    assert_eq!(grid.get(f.voxel), f.material);
                    // The hit face's neighbour is where the ray came from, so it is not inside the hit voxel.
                    let _: Face = f.face;
                }
                (f, b) => panic!("world {world_index} ray {ray_index} {ray:?}: dda {f:?} brute force {b:?}"),
            }
        }
    }
    assert!(hits > 1500, "too few hits to mean anything: {hits} of {rays}");
    assert!(ties * 200 < hits, "edge ties should be rare: {ties} of {hits}");
}

#[test]
fn hit_face_points_back_along_the_ray() {
    let mut grid = BrickGrid::new(UVec3::splat(32));
    grid.fill_box(IVec3::new(10, 10, 10), IVec3::new(20, 20, 20), 1).unwrap();
    let cases = [
        (Vec3::new(0.5, 15.5, 15.5), Vec3::X, Face(1), IVec3::new(10, 15, 15), 9.5),
        (Vec3::new(31.5, 15.5, 15.5), Vec3::NEG_X, Face(0), IVec3::new(19, 15, 15), 11.5),
        (Vec3::new(15.5, 31.0, 15.5), Vec3::NEG_Y, Face(2), IVec3::new(15, 19, 15), 11.0),
        (Vec3::new(15.5, 15.5, -40.0), Vec3::Z, Face(5), IVec3::new(15, 15, 10), 50.0),
    ];
    for (origin, dir, face, voxel, distance) in cases {
        let hit = trace(&grid, &Ray::new(origin, dir), f32::INFINITY).expect("hit");
        assert_eq!(hit.face, face, "from {origin}");
        assert_eq!(hit.voxel, voxel, "from {origin}");
        assert!((hit.distance - distance).abs() < 1e-5, "from {origin}: {}", hit.distance);
        assert_eq!(hit.face.normal(), -dir.as_ivec3());
    }
    // Starting inside a solid voxel hits it at distance zero.
    let hit = trace(&grid, &Ray::new(Vec3::splat(15.5), Vec3::X), f32::INFINITY).unwrap();
    assert_eq!((hit.voxel, hit.distance), (IVec3::splat(15), 0.0));
    // A ray that ends before the box misses.
    assert!(trace(&grid, &Ray::new(Vec3::new(0.5, 15.5, 15.5), Vec3::X), 9.0).is_none());
}

#[test]
fn a_subnormal_direction_component_on_a_boundary_plane_gives_a_finite_hit() {
    let mut grid = BrickGrid::new(UVec3::splat(16));
    grid.fill_box(IVec3::new(0, 0, 0), IVec3::new(16, 1, 16), 1).unwrap();
    // Origin exactly on voxel planes in x and z; the z component is subnormal (its reciprocal is infinite).
    let ray = Ray::new(Vec3::new(4.0, 8.0, 4.0), Vec3::new(0.3, -1.0, 1.0e-39));
    let hit = trace(&grid, &ray, f32::INFINITY).expect("the ray reaches the floor");
    assert!(hit.distance.is_finite(), "{hit:?}");
    assert_eq!(hit.voxel.y, 0);
}
