//! The MAVLink 2 signing secret: 32 bytes shared by the autopilot and us.
//!
//! Key file format: 64 hexadecimal digits (the 32 bytes), optionally followed by a newline; the
//! file must not be readable or writable by group or others (mode `0600` or `0400`). A key made
//! from a passphrase is the SHA-256 of the passphrase's UTF-8 bytes, what MAVProxy's
//! `signing setup PASSPHRASE` and Mission Planner send to the autopilot, so the same passphrase
//! gives both sides the same key.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

/// Length of the secret key in bytes (MAVLink 2 signing uses a 256-bit key).
pub const SIGNING_KEY_LEN: usize = 32;
/// Key file bytes read at most: 64 hex digits and a line ending, with room for `\r\n` and spaces.
const MAX_KEY_FILE_BYTES: u64 = 128;
/// Permission bits that must be clear: anything for group and others.
const GROUP_OTHER_BITS: u32 = 0o077;

/// The 32-byte signing secret. Its `Debug` output never shows the bytes.
#[derive(Clone, PartialEq, Eq)]
pub struct SigningKey([u8; SIGNING_KEY_LEN]);

impl fmt::Debug for SigningKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("SigningKey(..)")
    }
}

/// Why a key file was refused.
#[derive(Debug, thiserror::Error)]
pub enum KeyError {
    /// The file could not be opened or read.
    #[error("signing key file {path}: {cause}")]
    Read {
        /// The key file.
        path: PathBuf,
        /// The OS error.
        cause: std::io::Error,
    },
    /// Group or others may read or write the file.
    #[error(
        "signing key file {path}: mode {mode:04o} lets group or others access the secret; \
         allow only its owner (chmod 600 {path})"
    )]
    Permissions {
        /// The key file.
        path: PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// The content is not 64 hex digits.
    #[error("signing key file {path}: {reason} (expected 64 hexadecimal digits, the 32-byte key)")]
    Format {
        /// The key file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
}

impl SigningKey {
    /// The key from its 32 bytes.
    pub fn from_bytes(bytes: [u8; SIGNING_KEY_LEN]) -> SigningKey {
        SigningKey(bytes)
    }

    /// The key of a passphrase: SHA-256 of its UTF-8 bytes (as MAVProxy `signing setup`).
    pub fn from_passphrase(passphrase: &str) -> SigningKey {
        SigningKey(Sha256::digest(passphrase.as_bytes()).into())
    }

    /// Parses 64 hex digits (surrounding white space ignored).
    pub fn from_hex(text: &str) -> Result<SigningKey, String> {
        let text = text.trim();
        if text.len() != 2 * SIGNING_KEY_LEN {
            return Err(format!("{} characters", text.len()));
        }
        let mut key = [0u8; SIGNING_KEY_LEN];
        for (i, byte) in key.iter_mut().enumerate() {
            let digits = text.get(2 * i..2 * i + 2).ok_or("not ASCII")?;
            *byte = u8::from_str_radix(digits, 16)
                .map_err(|_| format!("{digits:?} at character {} is not hexadecimal", 2 * i))?;
        }
        Ok(SigningKey(key))
    }

    /// The key as 64 lowercase hex digits (the key file's content).
    pub fn to_hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// The raw bytes, for computing signatures.
    pub fn bytes(&self) -> &[u8; SIGNING_KEY_LEN] {
        &self.0
    }

    /// Reads a key file, refusing one that group or others may access.
    pub fn load(path: &Path) -> Result<SigningKey, KeyError> {
        use std::os::unix::fs::PermissionsExt;
        let read_err = |cause| KeyError::Read {
            path: path.to_path_buf(),
            cause,
        };
        let file = std::fs::File::open(path).map_err(read_err)?;
        let mode = file.metadata().map_err(read_err)?.permissions().mode() & 0o7777;
        if mode & GROUP_OTHER_BITS != 0 {
            return Err(KeyError::Permissions {
                path: path.to_path_buf(),
                mode,
            });
        }
        let mut bytes = Vec::new();
        file.take(MAX_KEY_FILE_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(read_err)?;
        let format_err = |reason: String| KeyError::Format {
            path: path.to_path_buf(),
            reason,
        };
        if bytes.len() as u64 > MAX_KEY_FILE_BYTES {
            return Err(format_err(format!(
                "longer than {MAX_KEY_FILE_BYTES} bytes"
            )));
        }
        let text = std::str::from_utf8(&bytes).map_err(|_| format_err("not text".into()))?;
        SigningKey::from_hex(text).map_err(format_err)
    }

    /// Writes the key file with mode 0600, refusing to replace an existing file.
    pub fn save(&self, path: &Path) -> Result<(), KeyError> {
        use std::io::Write;
        use std::os::unix::fs::OpenOptionsExt;
        let write_err = |cause| KeyError::Read {
            path: path.to_path_buf(),
            cause,
        };
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(path)
            .map_err(write_err)?;
        writeln!(file, "{}", self.to_hex()).map_err(write_err)?;
        file.sync_all().map_err(write_err)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    fn temp_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hubtrack-key-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn passphrase_key_is_sha256_of_the_passphrase() {
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        assert_eq!(
            SigningKey::from_passphrase("abc").to_hex(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn key_file_round_trip_and_permissions() {
        let path = temp_path("ok.key");
        let _ = std::fs::remove_file(&path);
        let key = SigningKey::from_passphrase("hubtrack");
        key.save(&path).unwrap();
        assert_eq!(
            std::fs::metadata(&path).unwrap().permissions().mode() & 0o777,
            0o600
        );
        assert_eq!(SigningKey::load(&path).unwrap(), key);
        // Never replaced.
        assert!(key.save(&path).is_err());
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();
        let err = SigningKey::load(&path).unwrap_err().to_string();
        assert!(
            err.contains(&path.display().to_string()) && err.contains("0644"),
            "{err}"
        );
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn malformed_key_files_are_named() {
        let path = temp_path("bad.key");
        for (content, why) in [
            (&b"abc"[..], "3 characters"),
            (&[b'g'; 64][..], "not hexadecimal"),
            (&[0xFFu8; 64][..], "not text"),
            (&[b'0'; 200][..], "longer than"),
        ] {
            let _ = std::fs::remove_file(&path);
            std::fs::write(&path, content).unwrap();
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
            let err = SigningKey::load(&path).unwrap_err().to_string();
            assert!(
                err.contains(why) && err.contains(&path.display().to_string()),
                "{err}"
            );
        }
        std::fs::remove_file(&path).unwrap();
        let err = SigningKey::load(&path).unwrap_err().to_string();
        assert!(err.contains("bad.key"), "{err}");
        // Multi-byte characters never split a digit pair.
        assert!(SigningKey::from_hex(&"é".repeat(32)).is_err());
    }

    #[test]
    fn debug_hides_the_secret() {
        let key = SigningKey::from_bytes([0xAB; 32]);
        assert!(!format!("{key:?}").contains("ab"));
    }
}
