//! Hostile input: random corruptions of valid world files and scene recipes are rejected with one clear error
//! line or load as a valid world, never a panic (proptest as a fuzzer over the loaders).

use glowbrick::world::format::{parse_world, world_to_string};
use glowbrick::world::scene::{generated_world, parse_recipe};
use proptest::prelude::*;
use std::sync::OnceLock;

fn valid_world() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| world_to_string(&generated_world(4, bevy::math::UVec3::new(24, 16, 24)).unwrap()))
}

fn valid_recipe() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| {
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/letters.ron")).unwrap()
    })
}

/// One corruption of a text: overwrite, insert, delete, or duplicate a span.
#[derive(Clone, Debug)]
enum Mutation {
    Overwrite(usize, u8),
    Insert(usize, String),
    Delete(usize, usize),
    Duplicate(usize, usize),
}

fn apply(text: &str, mutations: &[Mutation]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for m in mutations {
        let n = bytes.len().max(1);
        match m {
            Mutation::Overwrite(at, b) => {
                let i = at % n;
                if i < bytes.len() {
                    bytes[i] = *b;
                }
            }
            Mutation::Insert(at, s) => {
                let i = at % (bytes.len() + 1);
                bytes.splice(i..i, s.bytes());
            }
            Mutation::Delete(at, len) => {
                let i = at % n;
                let end = (i + len).min(bytes.len());
                bytes.drain(i.min(end)..end);
            }
            Mutation::Duplicate(at, len) => {
                let i = at % n;
                let end = (i + len).min(bytes.len());
                let span: Vec<u8> = bytes[i.min(end)..end].to_vec();
                bytes.splice(end..end, span);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let tokens = prop_oneof![
        Just("(".to_string()),
        Just(")".to_string()),
        Just("[".to_string()),
        Just(",".to_string()),
        Just("99999999999".to_string()),
        Just("-1".to_string()),
        Just("NaN".to_string()),
        Just("inf".to_string()),
        Just("\"".to_string()),
        Just("Uniform(".to_string()),
        Just("Runs([(600, 1)])".to_string()),
        Just("size: (2048, 2048, 2048),".to_string()),
        "[a-z:,()0-9 ]{0,12}",
    ];
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Mutation::Overwrite(a, b)),
        (any::<usize>(), tokens).prop_map(|(a, s)| Mutation::Insert(a, s)),
        (any::<usize>(), 0usize..64).prop_map(|(a, l)| Mutation::Delete(a, l)),
        (any::<usize>(), 0usize..256).prop_map(|(a, l)| Mutation::Duplicate(a, l)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn corrupted_world_files_never_panic(mutations in prop::collection::vec(mutation(), 1..6)) {
        let text = apply(valid_world(), &mutations);
        match parse_world(&text, "fuzz.ron") {
            Ok(world) => prop_assert!(world.grid.size().max_element() <= 2048),
            Err(e) => {
                let line = e.to_string();
                prop_assert!(line.starts_with("fuzz.ron") && !line.contains('\n'), "{}", line);
            }
        }
    }

    #[test]
    fn corrupted_recipes_never_panic(mutations in prop::collection::vec(mutation(), 1..6)) {
        let text = apply(valid_recipe(), &mutations);
        if let Err(e) = parse_recipe(&text, "fuzz-recipe.ron") {
            let line = e.to_string();
            prop_assert!(line.starts_with("fuzz-recipe.ron") && !line.contains('\n'), "{}", line);
        }
    }
}

/// The fuzzers start from inputs that load, and a harmless corruption (inside a comment) still loads.
#[test]
fn the_fuzzed_inputs_are_valid_to_begin_with() {
    assert!(parse_world(valid_world(), "w.ron").is_ok());
    assert!(parse_recipe(valid_recipe(), "r.ron").is_ok());
    let harmless = apply(valid_recipe(), &[Mutation::Overwrite(5, b'x')]);
    assert!(parse_recipe(&harmless, "r.ron").is_ok(), "a change inside the first comment must not matter");
}
