//! The camera–turbine envelope at the approach's target: can the camera see the spinner whole
//! from where the approach stops? Checked once at start-up, from the calibration, the turbine
//! profile and the target distance.
//!
//! Close in, distance comes from the spinner's rim and the hub is centred on the spinner; a
//! spinner wider than the camera's narrower field of view at the target leaves only part of its
//! rim in the frame, and the approach's last metres run on whatever is left (`fly --random-setup`:
//! 9 of 15 such flights ended at the target, 36 of 45 of the others; seed 44, a 4.2 m spinner
//! through a 60° 16:9 lens, passed 3.9 m from the rotor plane).

use hubtrack_types::setup::{CameraModel, TurbineSetup};

/// How the spinner fits the frame at the target distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpinnerFit {
    /// The angle the spinner spans seen head-on from the target, degrees.
    pub spinner_deg: f64,
    /// The camera's field of view across its narrower image direction, degrees.
    pub narrow_fov_deg: f64,
    /// The approach's target distance in front of the hub, m.
    pub target_m: f64,
    /// The closest distance at which the spinner still fits the narrower field of view, m.
    pub closest_fit_m: f64,
}

impl SpinnerFit {
    /// The fit of `turbine`'s spinner in `camera` at `target_m` in front of the hub.
    pub fn of(camera: &CameraModel, turbine: &TurbineSetup, target_m: f64) -> SpinnerFit {
        let radius = turbine.spinner_diameter_m / 2.0;
        let fov = camera.narrow_fov_rad();
        SpinnerFit {
            spinner_deg: 2.0 * (radius / target_m).atan().to_degrees(),
            narrow_fov_deg: fov.to_degrees(),
            target_m,
            closest_fit_m: radius / (fov / 2.0).tan(),
        }
    }

    /// The spinner fits the frame at the target.
    pub fn fits(&self) -> bool {
        self.spinner_deg <= self.narrow_fov_deg
    }

    /// What an operator is told when it does not.
    pub fn warning(&self) -> Option<String> {
        (!self.fits()).then(|| {
            format!(
                "at the {:.1} m target the spinner spans {:.0}°, wider than the camera's narrower \
                 field of view ({:.0}°): its rim leaves the frame and the last metres of the \
                 approach run on partial views. Fly a wider lens, or a target of at least {:.1} m \
                 (control.approach.target_distance_m)",
                self.target_m, self.spinner_deg, self.narrow_fov_deg, self.closest_fit_m
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_spinner_through_a_narrow_lens_does_not_fit_at_5_m() {
        let turbine = |d: f64| TurbineSetup {
            spinner_diameter_m: d,
            ..TurbineSetup::default()
        };
        // The built-in GoPro (66° across its height) and the thesis turbine's 3.2 m spinner.
        let gopro = SpinnerFit::of(&CameraModel::gopro_hero3(), &turbine(3.2), 5.0);
        assert!(gopro.fits() && gopro.warning().is_none(), "{gopro:?}");
        // A 60° 16:9 pinhole is 36° high: a 4.2 m spinner spans 45.6° at 5 m.
        let narrow = CameraModel::pinhole(1280, 720, 60.0);
        let fit = SpinnerFit::of(&narrow, &turbine(4.2), 5.0);
        assert!((fit.narrow_fov_deg - 35.98).abs() < 0.05, "{fit:?}");
        assert!((fit.spinner_deg - 45.57).abs() < 0.05, "{fit:?}");
        let warning = fit.warning().expect("warned");
        assert!(
            warning.contains("46°") && warning.contains("36°") && warning.contains("6.5 m"),
            "{warning}"
        );
        // From the closest distance it names, it fits.
        assert!(SpinnerFit::of(&narrow, &turbine(4.2), fit.closest_fit_m + 1e-6).fits());
    }
}
