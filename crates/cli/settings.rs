//! One settings value for the whole pipeline, read the same way by every command.
//!
//! A settings file is TOML with an `[ssl]` table (the fields of [`ssl::SslConfig`]), an
//! `[iasm]` table (the fields of [`asm::IasmConfig`]) and an optional top-level `array`
//! (a preset name or an array file); every key is optional and defaults as documented on
//! those types. Flags given on the command line override the file, and only flags that
//! were given do: a flag's absence never overwrites a value from the file.
//!
//! ```toml
//! array = "iasm6"
//! [ssl]
//! method = "mvdr"
//! frame_len = 4096
//! [iasm]
//! num_doas = 3
//! refine = true
//! ```
//!
//! N, the number of DoAs per stop, is one quantity with two names: the SSL reports
//! `ssl.num_peaks` DoAs and the mapper accepts `iasm.num_doas`. A file that sets one sets
//! both; a file that sets both to different values is refused; `--num` sets both.

use std::path::Path;

use anyhow::{Context, Result, bail};
use asm::IasmConfig;
use serde::{Deserialize, Serialize};
use ssl::{MicArray, SslConfig};

/// The array used when neither the settings file nor `--array` names one.
pub const DEFAULT_ARRAY: &str = "iasm6";

/// Every setting of the pipeline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The microphone array: a preset name or a TOML/JSON array file. Default: `iasm6`.
    pub array: Option<String>,
    /// The SSL front end.
    pub ssl: SslConfig,
    /// The mapper.
    pub iasm: IasmConfig,
}

impl Settings {
    /// Parses a settings file's text (see the module docs for the rules on N).
    ///
    /// # Errors
    /// Malformed TOML, unknown keys, or two different values of N.
    pub fn from_toml(text: &str) -> Result<Self> {
        let raw: toml::Table =
            toml::from_str(text).map_err(|e| anyhow::anyhow!("{}", e.message()))?;
        let mut s: Settings = raw
            .clone()
            .try_into()
            .map_err(|e: toml::de::Error| anyhow::anyhow!("{}", e.message()))?;
        let has = |table: &str, key: &str| {
            raw.get(table)
                .and_then(toml::Value::as_table)
                .is_some_and(|t| t.contains_key(key))
        };
        match (has("ssl", "num_peaks"), has("iasm", "num_doas")) {
            (true, true) if s.ssl.num_peaks != s.iasm.num_doas => bail!(
                "ssl.num_peaks = {} but iasm.num_doas = {}: both are N, the DoAs per stop; set one",
                s.ssl.num_peaks,
                s.iasm.num_doas
            ),
            (true, false) => s.iasm.num_doas = s.ssl.num_peaks,
            (false, true) => s.ssl.num_peaks = s.iasm.num_doas,
            _ => {}
        }
        Ok(s)
    }

    /// Reads a settings file, or the defaults when `path` is `None`.
    ///
    /// # Errors
    /// A file that cannot be read or is refused, named.
    pub fn load(path: Option<&Path>) -> Result<Self> {
        let Some(p) = path else {
            return Ok(Self::default());
        };
        let text = std::fs::read_to_string(p)
            .with_context(|| format!("reading settings {}", p.display()))?;
        Self::from_toml(&text).with_context(|| format!("settings {}", p.display()))
    }

    /// Sets N, the DoAs per stop, for the SSL and the mapper alike.
    pub fn set_num(&mut self, n: usize) {
        self.ssl.num_peaks = n;
        self.iasm.num_doas = n;
    }

    /// The array these settings name.
    ///
    /// # Errors
    /// An unknown preset or an unreadable array file.
    pub fn mic_array(&self) -> Result<MicArray> {
        Ok(MicArray::from_spec(
            self.array.as_deref().unwrap_or(DEFAULT_ARRAY),
        )?)
    }

    /// Checks both configurations.
    ///
    /// # Errors
    /// The first value refused.
    pub fn validate(&self) -> Result<()> {
        self.ssl.validate().context("[ssl]")?;
        self.iasm.validate().context("[iasm]")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_file_gives_the_defaults() {
        assert_eq!(Settings::from_toml("").unwrap(), Settings::default());
    }

    #[test]
    fn either_name_of_n_sets_both() {
        let s = Settings::from_toml("[ssl]\nnum_peaks = 3\n").unwrap();
        assert_eq!((s.ssl.num_peaks, s.iasm.num_doas), (3, 3));
        let s = Settings::from_toml("[iasm]\nnum_doas = 2\n").unwrap();
        assert_eq!((s.ssl.num_peaks, s.iasm.num_doas), (2, 2));
        let e = Settings::from_toml("[ssl]\nnum_peaks = 3\n[iasm]\nnum_doas = 4\n").unwrap_err();
        assert!(format!("{e:#}").contains("num_peaks = 3"), "{e:#}");
    }

    #[test]
    fn unknown_keys_are_named() {
        // A flat SSL file (the old format) is refused with the key it does not know.
        let e = Settings::from_toml("frame_len = 4096\n").unwrap_err();
        assert!(format!("{e:#}").contains("frame_len"), "{e:#}");
        let e = Settings::from_toml("[iasm]\nsigma = 5\n").unwrap_err();
        assert!(format!("{e:#}").contains("sigma"), "{e:#}");
    }
}
