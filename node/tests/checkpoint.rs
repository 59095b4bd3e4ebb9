//! The online learner's checkpoints: written atomically (a write that
//! fails midway leaves the previous checkpoint whole), read back equal,
//! and refused for another rover, columns or kind, naming the field.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::Write as _;

use gpodo_node::checkpoint::{Checkpoint, CheckpointError, sha256_hex};
use gpodo_regressors::RegressorSpec;
use gpodo_regressors::model_file::{ModelFile, Provenance};
use gpodo_traits::{ResidualDataset, SampleMatrix};

/// An ILGR fitted on `n` rows of a smooth residual of two inputs.
fn ilgr(n: usize) -> ModelFile {
    let inputs: Vec<f64> = (0..2 * n).map(|i| (i as f64 * 0.37).sin()).collect();
    let targets: Vec<f64> = (0..n)
        .flat_map(|i| {
            let (a, b) = (inputs[2 * i], inputs[2 * i + 1]);
            [0.01 * a, -0.005 * b, 0.002 * a * b]
        })
        .collect();
    let data = ResidualDataset::new(
        SampleMatrix::from_row_major(n, 2, inputs).unwrap(),
        SampleMatrix::from_row_major(n, 3, targets).unwrap(),
        vec!["cmd_v".into(), "pitch".into()],
        ["res_vx", "res_vy", "res_vz"].map(String::from).to_vec(),
    )
    .unwrap();
    let spec: RegressorSpec = serde_json::from_str(r#"{"kind": "ilgr"}"#).unwrap();
    ModelFile::fit(&spec, &data, None, Provenance::default())
        .unwrap()
        .0
}

/// A checkpoint as written (ILGR's caches, rebuilt on reading, are not).
fn json(c: &Checkpoint) -> String {
    serde_json::to_string(c).unwrap()
}

#[test]
fn the_hash_is_sha256() {
    assert_eq!(
        sha256_hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
}

#[test]
fn a_checkpoint_reads_back_equal_and_is_refused_for_another_robot() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("learner.json");
    let written = Checkpoint::new(ilgr(40), sha256_hex(b"rover: exoter"), 40);
    assert_eq!(written.key.kind, "ilgr");
    written.write(&path).unwrap();
    let read = Checkpoint::read(&path).unwrap();
    assert_eq!(json(&read), json(&written));
    read.check(&path, &written.key).unwrap();
    let other_rover = Checkpoint::new(ilgr(40), sha256_hex(b"rover: husky"), 40).key;
    let Err(CheckpointError::Mismatch { field, .. }) = read.check(&path, &other_rover) else {
        panic!("another rover accepted");
    };
    assert_eq!(field, "rover_sha256");
    let mut other_columns = written.key.clone();
    other_columns.input_columns.reverse();
    let e = read.check(&path, &other_columns).unwrap_err();
    assert!(e.to_string().contains("`input_columns`"), "{e}");
    let mut other_kind = written.key.clone();
    other_kind.kind = "sparse_spectrum".into();
    let e = read.check(&path, &other_kind).unwrap_err();
    assert!(e.to_string().contains("`kind` is ilgr"), "{e}");
}

#[test]
fn a_write_that_fails_midway_leaves_the_previous_checkpoint_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("learner.json");
    let first = Checkpoint::new(ilgr(30), sha256_hex(b"rover"), 30);
    first.write(&path).unwrap();
    let second = Checkpoint::new(ilgr(60), sha256_hex(b"rover"), 60);
    // Half the bytes written, then the disk fails.
    let e = second
        .write_with(&path, |file, bytes| {
            file.write_all(&bytes[..bytes.len() / 2])?;
            Err(std::io::Error::other("injected: disk full"))
        })
        .unwrap_err();
    assert!(e.to_string().contains("injected"), "{e}");
    assert_eq!(json(&Checkpoint::read(&path).unwrap()), json(&first));
    // No temporary file is left beside it.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["learner.json".to_string()]);
    // The next write goes through, and a truncated file is refused.
    second.write(&path).unwrap();
    assert_eq!(Checkpoint::read(&path).unwrap().targets_learned, 60);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    assert!(matches!(
        Checkpoint::read(&path),
        Err(CheckpointError::Invalid { .. })
    ));
}
