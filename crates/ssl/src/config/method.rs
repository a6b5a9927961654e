//! The angular-spectrum methods by name.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::ConfigError;

/// The angular-spectrum method, chosen at run time by name.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Generalised cross-correlation with phase transform (Knapp & Carter 1976).
    GccPhat,
    /// Minimum-variance distortionless response, per microphone pair (Capon 1969).
    #[default]
    Mvdr,
    /// Steered response power with phase transform over all microphones (DiBiase 2000):
    /// the block's cross-spectra whitened, then steered.
    SrpPhat,
    /// MUSIC (Schmidt 1986): the noise subspace of the full spatial covariance per bin;
    /// bins summed as they come, so the sharpest bins dominate.
    Music,
    /// MUSIC with every bin's pseudo-spectrum normalised to a peak of 1 before the bins
    /// are summed (Salvati, Drioli & Foresti 2014), so every bin votes alike.
    #[serde(rename = "normmusic", alias = "norm-music")]
    NormMusic,
    /// Test of orthogonality of projected subspaces (Yoon, Kaplan & McClellan 2006): the
    /// signal subspace of the loudest bin, carried to every other bin along each
    /// direction, tested against that bin's noise subspace. One spectrum per recording.
    Tops,
    /// Coherent signal-subspace method (Wang & Kaveh 1985): every bin's covariance focused
    /// onto the loudest bin and summed, then MUSIC there. One spectrum per recording.
    Cssm,
    /// Weighted average of signal subspaces (di Claudio & Parisi 2001): every bin's
    /// weighted signal subspace focused onto the loudest bin, then MUSIC there. One
    /// spectrum per recording.
    Waves,
}

impl Method {
    /// Every method, in report order.
    pub const ALL: [Method; 8] = [
        Method::GccPhat,
        Method::Mvdr,
        Method::SrpPhat,
        Method::Music,
        Method::NormMusic,
        Method::Tops,
        Method::Cssm,
        Method::Waves,
    ];

    /// The methods that pool short blocks of frames ([`crate::SslConfig::block_frames`]): all but
    /// the coherent wideband ones ([`Method::COHERENT`]).
    pub const BLOCKWISE: [Method; 5] = [
        Method::GccPhat,
        Method::Mvdr,
        Method::SrpPhat,
        Method::Music,
        Method::NormMusic,
    ];

    /// The coherent wideband subspace methods, which take one spectrum of the whole
    /// recording (their per-bin statistics need more snapshots than a block holds; see
    /// [`crate::coherent`]).
    pub const COHERENT: [Method; 3] = [Method::Tops, Method::Cssm, Method::Waves];

    /// The two methods of the paper's Table I (MBSS Locate's GCC-PHAT and MVDR).
    pub const PAPER: [Method; 2] = [Method::GccPhat, Method::Mvdr];

    /// The stable short name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::GccPhat => "gcc-phat",
            Method::Mvdr => "mvdr",
            Method::SrpPhat => "srp-phat",
            Method::Music => "music",
            Method::NormMusic => "normmusic",
            Method::Tops => "tops",
            Method::Cssm => "cssm",
            Method::Waves => "waves",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = ConfigError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "gcc-phat" | "gccphat" | "gcc_phat" => Ok(Method::GccPhat),
            "mvdr" => Ok(Method::Mvdr),
            "srp-phat" | "srpphat" | "srp_phat" | "srp" => Ok(Method::SrpPhat),
            "music" => Ok(Method::Music),
            "normmusic" | "norm-music" | "norm_music" => Ok(Method::NormMusic),
            "tops" => Ok(Method::Tops),
            "cssm" => Ok(Method::Cssm),
            "waves" => Ok(Method::Waves),
            _ => Err(ConfigError::UnknownMethod(s.to_owned())),
        }
    }
}
