//! A held-out check: how far another log of the same sensor (data the diagnosis did not see) lies
//! from the original model's band and from the corrected model's band.

use crate::error::DiagnoseError;
use crate::gap::gap;
use crate::input::LogInput;
use crate::measure::{measure, restrict};
use crate::report::{Diagnosis, HeldOutGap};
use std::collections::BTreeMap;

impl Diagnosis {
    /// The gap of another log of the same rate and length as a diagnosed run (data the diagnosis did
    /// not see) against the original model's band and the corrected model's band of one log, per
    /// channel.
    pub fn check(
        &self,
        log: &LogInput,
    ) -> Result<BTreeMap<noise::Channel, HeldOutGap>, DiagnoseError> {
        let samples = log.validate()?;
        let shape_error = || DiagnoseError::CheckShape {
            samples,
            dt_s: log.dt_s,
            expected_samples: self.log_bands.first().map_or(0, |b| b.samples),
            expected_dt_s: self.dt_s,
        };
        let bands = self.log_bands.iter().find(|b| b.samples == samples);
        let Some(bands) = bands.filter(|_| (log.dt_s - self.dt_s).abs() <= 1e-12 * self.dt_s)
        else {
            return Err(shape_error());
        };
        // The same time-domain corrections as the diagnosed log (outliers, temperature, transient).
        let pre = crate::detect::preprocess_log(log, &self.model_final);
        let corrected = log.with_channels(&pre.channels);
        let (grid_m, measured) = measure(&corrected, self.tau_min_s);
        let mut out = BTreeMap::new();
        for (c, m) in measured.iter() {
            let (Some(m), Some(b0), Some(b1)) = (
                m.as_ref(),
                bands.initial[c].as_ref(),
                bands.corrected[c].as_ref(),
            ) else {
                continue;
            };
            if grid_m != self.grid_m {
                return Err(shape_error());
            }
            out.insert(
                c,
                HeldOutGap {
                    gap_model: gap(&m.curve, &restrict(b0, &m.idx)).rms,
                    gap_corrected: gap(&m.curve, &restrict(b1, &m.idx)).rms,
                },
            );
        }
        Ok(out)
    }
}
