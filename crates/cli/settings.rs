//! One settings value for the whole pipeline, read the same way by every command.
//!
//! A settings file is TOML with an `[ssl]` table (the fields of [`ssl::SslConfig`]), an
//! `[iasm]` table (the fields of [`asm::IasmConfig`]), an optional top-level `array`
//! (a preset name or an array file) and `channels` (which channels of each file are the
//! array's microphones, [`Settings::channels`]) and `noise` (a recording of the robot alone,
//! [`Settings::noise`]); every key is optional and defaults as documented on those types. Flags given on the command line override the file, and only flags that
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
//! `[iasm] profile = "paper"` starts the I-ASM parameters from the paper's algorithm
//! exactly (Table I; [`asm::Profile::Paper`]) instead of the default robust profile; keys in
//! the file override the profile's values either way.
//!
//! N, the number of DoAs per stop, is one quantity with two names: the SSL reports
//! `ssl.num_peaks` DoAs and the mapper accepts `iasm.num_doas`. A file that sets one sets
//! both; a file that sets both to different values is refused; `--num` sets both.

use std::path::Path;

use anyhow::{Context, Result, bail};
use asm::{IasmConfig, Profile};
use serde::{Deserialize, Serialize};
use ssl::{MicArray, SslConfig};

/// The array used when neither the settings file nor `--array` names one, nor the data set
/// holds an array file ([`DATASET_ARRAY_FILES`]).
pub const DEFAULT_ARRAY: &str = "iasm6";

/// The array file a data set folder may hold beside `audio/`, in the format of
/// [`ssl::MicArray::from_file`]; the first found is used. `iasm simulate` writes
/// `array.toml`.
pub const DATASET_ARRAY_FILES: [&str; 2] = ["array.toml", "array.json"];

/// The folder of a data set that holds the recording of the robot alone
/// ([`Settings::noise`]).
pub const DATASET_NOISE_DIR: &str = "noise";

/// Every setting of the pipeline.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The microphone array: a preset name or a TOML/JSON array file. Default: `iasm6`.
    pub array: Option<String>,
    /// The channels of each recording that are the array's microphones, in the array's
    /// order, counted from 1 as a file's channels are (`channels = [2, 3, 4, 5]`,
    /// `--channels 2-5`): for files that hold other channels too, as a ReSpeaker's
    /// firmware records its processed beam and its playback beside the microphones.
    /// Default: every channel, in the file's order.
    pub channels: Option<Vec<usize>>,
    /// A recording of the robot alone (a WAV: its fans running, no other source, a few
    /// seconds, with the same microphones and channels as the recordings): the robot's own
    /// noise, subtracted from every statistic of the SSL ([`ssl::noise`]). Default: none,
    /// or the data set's `noise/` recording ([`Settings::with_dataset_noise`]).
    pub noise: Option<std::path::PathBuf>,
    /// The SSL front end.
    pub ssl: SslConfig,
    /// The mapper.
    pub iasm: IasmConfig,
}

impl Settings {
    /// Parses a settings file's text (see the module docs for the rules on N and on
    /// profiles).
    ///
    /// # Errors
    /// Malformed TOML, unknown keys, or two different values of N.
    pub fn from_toml(text: &str) -> Result<Self> {
        Self::from_toml_with(text, None)
    }

    /// [`Settings::from_toml`], with the I-ASM profile `profile` when given (else the
    /// file's `[iasm] profile`, else [`Profile::Robust`]); the file's own `[iasm]` keys
    /// override the profile's values.
    ///
    /// # Errors
    /// As [`Settings::from_toml`].
    pub fn from_toml_with(text: &str, profile: Option<Profile>) -> Result<Self> {
        let msg = |e: toml::de::Error| anyhow::anyhow!("{}", e.message());
        let mut raw: toml::Table = toml::from_str(text).map_err(msg)?;
        let has = |raw: &toml::Table, table: &str, key: &str| {
            raw.get(table)
                .and_then(toml::Value::as_table)
                .is_some_and(|t| t.contains_key(key))
        };
        let has_peaks = has(&raw, "ssl", "num_peaks");
        let has_doas = has(&raw, "iasm", "num_doas");
        let mut iasm = match raw.remove("iasm") {
            Some(toml::Value::Table(t)) => t,
            Some(_) => bail!("iasm must be a table"),
            None => toml::Table::new(),
        };
        let file_profile = match iasm.remove("profile") {
            Some(v) => Some(Profile::deserialize(v).map_err(msg)?),
            None => None,
        };
        let profile = profile.or(file_profile).unwrap_or_default();
        let mut base = toml::Table::try_from(IasmConfig::profile(profile))?;
        base.extend(iasm);
        raw.insert("iasm".into(), toml::Value::Table(base));
        let mut s: Settings = match raw.clone().try_into() {
            Ok(s) => s,
            // A value of the wrong type: serde says what it expected but not where; the
            // key that fails alone is the one to name.
            Err(e) => bail!(
                "{}",
                bad_key(&raw).unwrap_or_else(|| e.message().to_owned())
            ),
        };
        match (has_peaks, has_doas) {
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
        Self::load_with(path, None)
    }

    /// [`Settings::load`] with the I-ASM profile `profile` when given (see
    /// [`Settings::from_toml_with`]).
    ///
    /// # Errors
    /// As [`Settings::load`].
    pub fn load_with(path: Option<&Path>, profile: Option<Profile>) -> Result<Self> {
        let Some(p) = path else {
            return Self::from_toml_with("", profile);
        };
        let text = std::fs::read_to_string(p)
            .with_context(|| format!("reading settings {}", p.display()))?;
        Self::from_toml_with(&text, profile).with_context(|| format!("settings {}", p.display()))
    }

    /// Sets N, the DoAs per stop, for the SSL and the mapper alike.
    pub fn set_num(&mut self, n: usize) {
        self.ssl.num_peaks = n;
        self.iasm.num_doas = n;
    }

    /// These settings, with the array file of the data set `dir` ([`DATASET_ARRAY_FILES`])
    /// when neither the settings file nor `--array` named an array: recordings whose
    /// folder says which microphones made them are not localised with the default array
    /// (a mismatch of channel counts is refused, but one of geometry would not be).
    pub fn with_dataset_array(mut self, dir: Option<&Path>) -> Self {
        if self.array.is_none()
            && let Some(dir) = dir
            && let Some(file) = DATASET_ARRAY_FILES
                .iter()
                .map(|name| dir.join(name))
                .find(|p| p.is_file())
        {
            self.array = Some(file.display().to_string());
        }
        self
    }

    /// These settings, with the data set `dir`'s recording of the robot alone (the one WAV
    /// in its `noise/` folder, which `iasm simulate` writes for a scene with sources on the
    /// robot) when no `noise` was given.
    ///
    /// # Errors
    /// A `noise/` folder that holds no WAV or several.
    pub fn with_dataset_noise(mut self, dir: Option<&Path>) -> Result<Self> {
        if self.noise.is_none()
            && let Some(dir) = dir
            && dir.join(DATASET_NOISE_DIR).is_dir()
        {
            let folder = dir.join(DATASET_NOISE_DIR);
            let wavs = crate::dataset::list_files(&folder, "wav")?;
            match wavs.as_slice() {
                [one] => self.noise = Some(one.clone()),
                [] => bail!("{}: no WAV of the robot alone", folder.display()),
                _ => bail!(
                    "{}: {} WAVs; the robot alone is one recording (or name it with --noise)",
                    folder.display(),
                    wavs.len()
                ),
            }
        }
        Ok(self)
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
        if let Some(c) = &self.channels {
            if c.is_empty() || c.contains(&0) {
                bail!("channels must list the microphones' channels, counted from 1 (got {c:?})");
            }
            if let Some(d) = c
                .iter()
                .find(|&&x| c.iter().filter(|&&y| y == x).count() > 1)
            {
                bail!("channels lists channel {d} twice: each microphone is one channel");
            }
        }
        self.ssl.validate().context("[ssl]")?;
        self.iasm.validate().context("[iasm]")?;
        Ok(())
    }
}

/// The first `[ssl]` or `[iasm]` key whose value does not deserialise on its own (on top of
/// the defaults), as `[table] key = value: what is wrong`.
fn bad_key(raw: &toml::Table) -> Option<String> {
    fn first<T: serde::de::DeserializeOwned>(
        name: &str,
        table: &toml::Table,
        base: &toml::Table,
    ) -> Option<String> {
        table.iter().find_map(|(k, v)| {
            let mut one = base.clone();
            one.insert(k.clone(), v.clone());
            toml::Value::Table(one)
                .try_into::<T>()
                .err()
                .map(|e| format!("[{name}] {k} = {v}: {}", e.message()))
        })
    }
    let table = |name: &str| raw.get(name).and_then(toml::Value::as_table);
    if let Some(t) = table("ssl")
        && let Some(e) = first::<SslConfig>("ssl", t, &toml::Table::new())
    {
        return Some(e);
    }
    let iasm = table("iasm")?;
    let base = toml::Table::try_from(IasmConfig::default()).ok()?;
    first::<IasmConfig>("iasm", iasm, &base)
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
    fn a_profile_is_a_base_that_the_files_keys_override() {
        let s = Settings::from_toml("[iasm]\nprofile = \"paper\"\n").unwrap();
        assert_eq!(s.iasm, IasmConfig::profile(Profile::Paper));
        let s = Settings::from_toml("[iasm]\nprofile = \"paper\"\nrefine = true\n").unwrap();
        assert!(s.iasm.refine);
        assert_eq!(s.iasm.min_observations, 1);
        // A profile given from outside (the command line) wins over the file's.
        let s = Settings::from_toml_with("[iasm]\nprofile = \"paper\"\n", Some(Profile::Robust))
            .unwrap();
        assert_eq!(s.iasm, IasmConfig::default());
        assert!(Settings::from_toml("[iasm]\nprofile = \"fast\"\n").is_err());
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
