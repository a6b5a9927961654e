use crate::error::ConfigError;

use super::Label;

/// DBSCAN parameters, unchecked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DbscanParams {
    /// Neighbourhood radius (m, `> 0`).
    pub eps: f64,
    /// Points (the point itself included) that make a neighbourhood dense (`>= 1`).
    pub min_pts: usize,
}

/// Checked DBSCAN parameters: clustering cannot fail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dbscan {
    pub(crate) eps: f64,
    pub(crate) min_pts: usize,
}

impl DbscanParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`ConfigError`] if `eps` is not positive and finite or `min_pts` is 0.
    pub fn check(self) -> Result<Dbscan, ConfigError> {
        if !(self.eps.is_finite() && self.eps > 0.0) {
            return Err(ConfigError::NotPositive {
                name: "DBSCAN eps",
                value: self.eps,
            });
        }
        if self.min_pts == 0 {
            return Err(ConfigError::Zero("DBSCAN min_pts"));
        }
        Ok(Dbscan {
            eps: self.eps,
            min_pts: self.min_pts,
        })
    }
}

impl Dbscan {
    /// Labels every point.
    pub fn cluster(&self, points: &[[f64; 2]]) -> Vec<Label> {
        super::dbscan(points, self.eps, self.min_pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eps_must_be_positive_and_min_pts_nonzero() {
        assert!(
            DbscanParams {
                eps: 0.0,
                min_pts: 3
            }
            .check()
            .is_err()
        );
        assert!(
            DbscanParams {
                eps: f64::NAN,
                min_pts: 3
            }
            .check()
            .is_err()
        );
        assert!(
            DbscanParams {
                eps: 0.1,
                min_pts: 0
            }
            .check()
            .is_err()
        );
        assert!(
            DbscanParams {
                eps: 0.1,
                min_pts: 1
            }
            .check()
            .is_ok()
        );
    }
}
