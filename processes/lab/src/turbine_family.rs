//! Families of turbine proportions. The fleet is what `hubtrack fly --random-setup` flies (what
//! real fleets vary); the learned yaw networks are trained on one part of it, the training
//! family, and scored on the rest, the held-out family (`hubtrack dataset --turbines`): thin and
//! thick towers and long overhangs are never shown in training.

use hubtrack_types::mutate::Rng;
use hubtrack_types::setup::TurbineSetup;

/// The ranges a family draws each proportion from (uniformly).
#[derive(Clone, Copy, Debug)]
pub struct TurbineRanges {
    /// Tower top diameter, m.
    pub tower_top_m: (f64, f64),
    /// Tower base over top diameter.
    pub taper: (f64, f64),
    /// Rotor radius, m.
    pub rotor_radius_m: (f64, f64),
    /// Hub height over the rotor radius (the rotor clears the ground), m.
    pub hub_above_rotor_m: (f64, f64),
    /// Spinner diameter, m.
    pub spinner_m: (f64, f64),
    /// Hub overhang, m.
    pub overhang_m: (f64, f64),
    /// Hub height above the tower top (half the nacelle's height: 0.8–1.5 times the thesis
    /// turbine's), m.
    pub hub_above_tower_top_m: (f64, f64),
    /// Nacelle width, length and front setback factors, each over the thesis turbine's scaled by
    /// the drawn hub height above the tower top over its own.
    pub nacelle_width_factor: (f64, f64),
    pub nacelle_length_factor: (f64, f64),
    pub nacelle_front_factor: (f64, f64),
}

/// What real fleets vary (`fly --random-setup`).
pub const FLEET: TurbineRanges = TurbineRanges {
    tower_top_m: (1.8, 3.5),
    taper: (1.4, 2.2),
    rotor_radius_m: (25.0, 63.0),
    hub_above_rotor_m: (25.0, 45.0),
    spinner_m: (2.4, 4.6),
    overhang_m: (3.0, 7.0),
    hub_above_tower_top_m: (1.4, 2.6),
    nacelle_width_factor: (0.85, 1.2),
    nacelle_length_factor: (0.8, 1.25),
    nacelle_front_factor: (0.6, 1.5),
};

/// The learned yaw networks' training family: the fleet without its thinnest and thickest
/// towers and its longest overhangs (the held-out family, e.g. the 1.8 m and 3.1 m towers of
/// `tests/data/held-out/`).
pub const TRAINING: TurbineRanges = TurbineRanges {
    tower_top_m: (2.0, 3.0),
    overhang_m: (3.0, 6.0),
    ..FLEET
};

/// The drawn nacelle's rear face lies at least this far behind the tower axis, metres.
const NACELLE_MIN_REAR_BEHIND_TOWER_M: f64 = 1.0;

/// Which turbines a set shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Family {
    /// The thesis turbine only.
    Thesis,
    /// The training family: the fleet's proportions with tower tops of 2.0–3.0 m and overhangs
    /// of 3–6 m.
    Training,
    /// The fleet outside the training family: tower tops of 1.8–2.0 or 3.0–3.5 m, or overhangs
    /// of 6–7 m.
    HeldOut,
}

fn uniform(r: &mut Rng, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * ((r.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

fn within(v: f64, (lo, hi): (f64, f64)) -> bool {
    (lo..=hi).contains(&v)
}

/// Draws one turbine from `ranges`, a valid profile (the nacelle on its tower).
pub fn draw(r: &mut Rng, ranges: &TurbineRanges) -> TurbineSetup {
    let top = uniform(r, ranges.tower_top_m);
    let base = top * uniform(r, ranges.taper);
    let rotor = uniform(r, ranges.rotor_radius_m);
    let hub_height = rotor + uniform(r, ranges.hub_above_rotor_m);
    let spinner = uniform(r, ranges.spinner_m);
    let overhang = uniform(r, ranges.overhang_m);
    let above_top = uniform(r, ranges.hub_above_tower_top_m);
    let thesis = TurbineSetup::default();
    let k = above_top / thesis.hub_above_tower_top_m;
    let nacelle_width = thesis.nacelle_width_m * k * uniform(r, ranges.nacelle_width_factor);
    let nacelle_front =
        thesis.nacelle_front_behind_hub_m * k * uniform(r, ranges.nacelle_front_factor);
    let nacelle_length = (thesis.nacelle_length_m * k * uniform(r, ranges.nacelle_length_factor))
        .max(overhang - nacelle_front + NACELLE_MIN_REAR_BEHIND_TOWER_M);
    let mut t = TurbineSetup {
        hub_height_m: hub_height,
        rotor_radius_m: rotor,
        tower_top_diameter_m: top,
        tower_base_diameter_m: base,
        hub_overhang_m: overhang,
        hub_above_tower_top_m: above_top,
        spinner_diameter_m: spinner,
        nacelle_width_m: nacelle_width,
        nacelle_length_m: nacelle_length,
        nacelle_front_behind_hub_m: nacelle_front,
        ..TurbineSetup::default()
    };
    t.name = describe(&t);
    t
}

/// Whether `t` lies in the yaw networks' training family.
pub fn in_training_family(t: &TurbineSetup) -> bool {
    within(t.tower_top_diameter_m, TRAINING.tower_top_m)
        && within(t.hub_overhang_m, TRAINING.overhang_m)
}

impl Family {
    /// The family of a turbine of the fleet: the training family or the rest.
    pub fn of_fleet_turbine(t: &TurbineSetup) -> Family {
        if in_training_family(t) {
            Family::Training
        } else {
            Family::HeldOut
        }
    }

    /// The family's name, as `--turbines` spells it and fly results report it.
    pub fn name(self) -> &'static str {
        match self {
            Family::Thesis => "thesis",
            Family::Training => "training",
            Family::HeldOut => "held-out",
        }
    }
}

/// The turbine of a set's scene `seed` (`None`: the thesis turbine, as drawn by the scene).
pub fn for_scene(family: Family, seed: u64) -> Option<TurbineSetup> {
    let mut r = Rng::new(seed);
    match family {
        Family::Thesis => None,
        Family::Training => Some(draw(&mut r, &TRAINING)),
        // A fleet draw lands outside the training family with probability ≈ 0.56.
        Family::HeldOut => {
            std::iter::repeat_with(|| draw(&mut r, &FLEET)).find(|t| !in_training_family(t))
        }
    }
}

/// One line for logs and result lines.
pub fn describe(t: &TurbineSetup) -> String {
    format!(
        "rotor {:.1} m, hub {:.0} m, tower {:.2}-{:.2} m, spinner {:.2} m, overhang {:.2} m, hub {:.2} m above the tower, nacelle {:.2} x {:.1} m from {:.2} m behind the hub",
        t.rotor_radius_m,
        t.hub_height_m,
        t.tower_top_diameter_m,
        t.tower_base_diameter_m,
        t.spinner_diameter_m,
        t.hub_overhang_m,
        t.hub_above_tower_top_m,
        t.nacelle_width_m,
        t.nacelle_length_m,
        t.nacelle_front_behind_hub_m
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_families_split_the_fleet_and_draw_valid_profiles() {
        for seed in 0..300 {
            let t = for_scene(Family::Training, seed).unwrap();
            t.validate().unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            assert!(in_training_family(&t), "seed {seed}: {}", t.name);
            let h = for_scene(Family::HeldOut, seed).unwrap();
            h.validate().unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            assert!(!in_training_family(&h), "seed {seed}: {}", h.name);
            assert!(within(h.tower_top_diameter_m, FLEET.tower_top_m));
            assert!(within(h.hub_overhang_m, FLEET.overhang_m));
        }
        assert!(for_scene(Family::Thesis, 1).is_none());
        // The names fly results report are those the command line accepts.
        for f in [Family::Thesis, Family::Training, Family::HeldOut] {
            let value = clap::ValueEnum::to_possible_value(&f).unwrap();
            assert_eq!(f.name(), value.get_name());
        }
        // The shipped held-out profiles lie outside the training family.
        for file in ["slim_1mw.toml", "tall_3mw.toml"] {
            let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/held-out/");
            let text = std::fs::read_to_string(format!("{path}{file}")).unwrap();
            let t: TurbineSetup = toml::from_str(&text).unwrap();
            assert!(!in_training_family(&t), "{file}");
        }
    }
}
