//! The committed fuzz corpus, replayed: every input of every target (the seeds, and every input that once
//! crashed, hung or over-allocated, under `corpus/<target>/`) goes through its reader, which must return. A
//! panic fails the test and names the file.
#![allow(
    clippy::disallowed_methods,
    reason = "the corpus is read whole, as the fuzzer hands an input to a target"
)]

use oeg_fuzz::{TARGETS, corpus_dir, run};

#[test]
fn every_corpus_input_returns_from_its_reader() {
    let mut counts = Vec::new();
    for target in TARGETS {
        let dir = corpus_dir().join(target.name());
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("entry").path())
            .collect();
        files.sort();
        assert!(!files.is_empty(), "{}: no corpus", dir.display());
        let mut accepted = 0;
        for file in &files {
            let data = std::fs::read(file).expect("readable");
            let outcome = std::panic::catch_unwind(|| run(target, &data));
            match outcome {
                Ok(ok) => accepted += usize::from(ok),
                Err(_) => panic!("{} panicked on {}", target.name(), file.display()),
            }
        }
        counts.push(format!(
            "{}: {} inputs, {accepted} accepted",
            target.name(),
            files.len()
        ));
        // Every target's seeds include inputs its reader accepts, so the corpus reaches past the first check.
        assert!(accepted > 0, "{}: no input accepted", target.name());
    }
    println!("{}", counts.join("\n"));
}
