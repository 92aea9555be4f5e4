//! Where replay writes: never over its input, never over an existing file unless asked.
//!
//! The recorder writes `OUTPUT.partial`; only a finished replay is moved to `OUTPUT`, so an
//! interrupted replay leaves the previous file (if any) as it was.

use anyhow::bail;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// Refuses an `output` that is the `input` (same path, a link to it, or the same file under
/// another name) or, unless `force`, a file that already exists.
pub fn check(input: &Path, output: &Path, force: bool) -> anyhow::Result<()> {
    let same_file = match (std::fs::metadata(input), std::fs::metadata(output)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    };
    if same_file {
        bail!(
            "-o {} is the recording being replayed ({}): choose another output file",
            output.display(),
            input.display()
        );
    }
    if output.is_dir() {
        bail!(
            "-o {} is a folder: name the output file (e.g. {})",
            output.display(),
            output.join("replay.mcap").display()
        );
    }
    if !force && std::fs::symlink_metadata(output).is_ok() {
        bail!(
            "-o {} already exists: choose another output file, or pass --force to replace it",
            output.display()
        );
    }
    Ok(())
}

/// The file the recorder writes while the replay runs.
pub fn partial(output: &Path) -> PathBuf {
    hubtrack_record::reader::partial_name(output)
}

/// Moves the finished `partial(output)` to `output`: replacing a file only with `force`, and
/// never the `input` (checked again: it may have been swapped in meanwhile).
pub fn publish(input: &Path, output: &Path, force: bool) -> anyhow::Result<()> {
    let tmp = partial(output);
    check(input, output, force)?;
    let moved = if force {
        std::fs::rename(&tmp, output)
    } else {
        // A hard link fails if `output` appeared meanwhile: nothing is replaced.
        std::fs::hard_link(&tmp, output).and_then(|()| std::fs::remove_file(&tmp))
    };
    moved.map_err(|e| {
        anyhow::anyhow!(
            "moving the replay {} to {}: {e} (the replay is kept in {})",
            tmp.display(),
            output.display(),
            tmp.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_input_and_existing_files_are_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.mcap");
        std::fs::write(&input, b"recording").unwrap();
        let e = check(&input, &input, true).unwrap_err().to_string();
        assert!(e.contains("is the recording being replayed"), "{e}");
        // The same file under another spelling and through a hard link.
        let dotted = dir.path().join(".").join("in.mcap");
        assert!(check(&input, &dotted, true).is_err());
        let link = dir.path().join("link.mcap");
        std::fs::hard_link(&input, &link).unwrap();
        assert!(check(&input, &link, true).is_err());
        let other = dir.path().join("other.mcap");
        std::fs::write(&other, b"old").unwrap();
        let e = check(&input, &other, false).unwrap_err().to_string();
        assert!(e.contains("already exists") && e.contains("--force"), "{e}");
        check(&input, &other, true).unwrap();
        check(&input, &dir.path().join("new.mcap"), false).unwrap();
        // Publishing: without --force an existing file stays, with it the replay replaces it.
        std::fs::write(partial(&other), b"new").unwrap();
        assert!(publish(&input, &other, false).is_err());
        assert_eq!(std::fs::read(&other).unwrap(), b"old");
        publish(&input, &other, true).unwrap();
        assert_eq!(std::fs::read(&other).unwrap(), b"new");
        assert!(!partial(&other).exists());
        assert_eq!(std::fs::read(&input).unwrap(), b"recording");
    }
}
