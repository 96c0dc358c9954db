//! A MagicaVoxel scene written byte by byte, for the CPU import test and the GPU lighting test (included by both
//! test binaries with `#[path]`).

/// A MagicaVoxel file as the editor saves it: two models, each under its own translation in a group, and an
/// emissive material. Chunks: SIZE/XYZI per model, RGBA, nTRN/nGRP/nSHP, MATL.
pub fn scene_graph_vox() -> Vec<u8> {
    fn chunk(id: &[u8; 4], content: &[u8]) -> Vec<u8> {
        let mut c = id.to_vec();
        c.extend((content.len() as u32).to_le_bytes());
        c.extend(0u32.to_le_bytes());
        c.extend(content);
        c
    }
    fn words(w: &[i32]) -> Vec<u8> {
        w.iter().flat_map(|x| x.to_le_bytes()).collect()
    }
    fn dict(pairs: &[(&str, &str)]) -> Vec<u8> {
        let mut d = words(&[pairs.len() as i32]);
        for (k, v) in pairs {
            for s in [k, v] {
                d.extend(words(&[s.len() as i32]));
                d.extend(s.as_bytes());
            }
        }
        d
    }
    let transform = |id: i32, child: i32, t: &str| {
        let mut c = words(&[id]);
        c.extend(dict(&[]));
        c.extend(words(&[child, -1, 0, 1]));
        c.extend(dict(&[("_t", t)]));
        chunk(b"nTRN", &c)
    };
    let shape = |id: i32, model: i32| {
        let mut c = words(&[id]);
        c.extend(dict(&[]));
        c.extend(words(&[1, model]));
        c.extend(dict(&[]));
        chunk(b"nSHP", &c)
    };
    let mut children = Vec::new();
    // Model 0: a 6 x 6 x 1 slab of colour 1 (the floor). Model 1: a 2 x 2 x 2 cube of colour 2 (the lamp).
    children.extend(chunk(b"SIZE", &words(&[6, 6, 1])));
    let slab: Vec<u8> = (0..36u8).flat_map(|i| [i % 6, i / 6, 0, 1]).collect();
    children.extend(chunk(b"XYZI", &[words(&[36]), slab].concat()));
    children.extend(chunk(b"SIZE", &words(&[2, 2, 2])));
    let cube: Vec<u8> = (0..8u8).flat_map(|i| [i & 1, (i >> 1) & 1, i >> 2, 2]).collect();
    children.extend(chunk(b"XYZI", &[words(&[8]), cube].concat()));
    let mut rgba = vec![200u8; 1024];
    rgba[4..8].copy_from_slice(&[255, 240, 200, 255]);
    children.extend(chunk(b"RGBA", &rgba));
    children.extend(transform(0, 1, "0 0 0"));
    let mut group = words(&[1]);
    group.extend(dict(&[]));
    group.extend(words(&[2, 2, 4]));
    children.extend(chunk(b"nGRP", &group));
    // The slab's centre at (3, 3, 0); the cube's at (3, 3, 5): it hangs 4 voxels above the slab's middle.
    children.extend(transform(2, 3, "3 3 0"));
    children.extend(shape(3, 0));
    children.extend(transform(4, 5, "3 3 5"));
    children.extend(shape(5, 1));
    let mut matl = words(&[2]);
    matl.extend(dict(&[("_type", "_emit"), ("_emit", "1.0"), ("_flux", "1")]));
    children.extend(chunk(b"MATL", &matl));
    let mut file = b"VOX ".to_vec();
    file.extend(words(&[150]));
    file.extend(b"MAIN");
    file.extend(words(&[0, children.len() as i32]));
    file.extend(children);
    file
}
