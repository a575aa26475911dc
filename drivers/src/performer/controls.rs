//! A performer's controls: the buttons and analog channels of its VRPN devices, named
//! `Device.index` (`Wand0.2`), their latest values and the changes the input phase saw
//! (their Lua side is `controls_api`).

use crate::vrpn::VrpnReading;
use std::collections::BTreeMap;

/// One control that changed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Change {
    /// A button went down (`true`) or up.
    Button(String, bool),
    /// An analog channel took a new value.
    Analog(String, f64),
}

/// The latest value of every control, and the changes not yet handed to handlers.
#[derive(Debug, Default)]
pub(crate) struct Controls {
    pub(crate) buttons: BTreeMap<String, bool>,
    pub(crate) analogs: BTreeMap<String, f64>,
    pub(crate) changes: Vec<Change>,
}

impl Controls {
    fn button(&mut self, name: String, pressed: bool) {
        if self.buttons.insert(name.clone(), pressed) != Some(pressed) {
            self.changes.push(Change::Button(name, pressed));
        }
    }

    /// Takes a button or analog report (others are not controls); `false` when it is
    /// refused: an analog report with a non-finite channel is not applied at all (NaN
    /// would differ from itself and fire a change on every report).
    pub(crate) fn apply(&mut self, r: &VrpnReading) -> bool {
        match r {
            VrpnReading::Button {
                device,
                button,
                pressed,
                ..
            } => self.button(format!("{device}.{button}"), *pressed),
            VrpnReading::Buttons {
                device, pressed, ..
            } => {
                for (i, p) in pressed.iter().enumerate() {
                    self.button(format!("{device}.{i}"), *p);
                }
            }
            VrpnReading::Analog { channels, .. } if channels.iter().any(|v| !v.is_finite()) => {
                return false;
            }
            VrpnReading::Analog {
                device, channels, ..
            } => {
                for (i, v) in channels.iter().enumerate() {
                    let name = format!("{device}.{i}");
                    if self.analogs.insert(name.clone(), *v) != Some(*v) {
                        self.changes.push(Change::Analog(name, *v));
                    }
                }
            }
            _ => {}
        }
        true
    }
}

/// Whether `name` matches `pattern`, where `*` stands for any run of characters.
pub(crate) fn glob(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((head, rest)) => {
            let Some(tail) = name.strip_prefix(head) else {
                return false;
            };
            (0..=tail.len())
                .filter(|&i| tail.is_char_boundary(i))
                .any(|i| glob(rest, &tail[i..]))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_match_runs_of_any_characters() {
        assert!(glob("Wand0.*", "Wand0.12"));
        assert!(glob("*", ""));
        assert!(glob("*.1", "Button0.1"));
        assert!(!glob("*.1", "Button0.10"));
        assert!(glob("W*0.*2", "Wand0.2"));
        assert!(!glob("Wand0.1", "Wand0.10"));
    }

    #[test]
    fn only_changes_are_events() {
        let mut c = Controls::default();
        let b = |pressed| VrpnReading::Button {
            device: "B".into(),
            button: 1,
            pressed,
            time: 0.0,
        };
        c.apply(&b(true));
        c.apply(&b(true));
        c.apply(&VrpnReading::Buttons {
            device: "B".into(),
            pressed: vec![false, true],
            time: 0.0,
        });
        c.apply(&VrpnReading::Analog {
            device: "A".into(),
            channels: vec![0.5],
            time: 0.0,
        });
        c.apply(&VrpnReading::Analog {
            device: "A".into(),
            channels: vec![0.5],
            time: 0.0,
        });
        assert_eq!(
            c.changes,
            vec![
                Change::Button("B.1".into(), true),
                Change::Button("B.0".into(), false),
                Change::Analog("A.0".into(), 0.5)
            ]
        );
    }

    #[test]
    fn non_finite_analog_reports_are_refused_whole() {
        let mut c = Controls::default();
        let a = |channels: Vec<f64>| VrpnReading::Analog {
            device: "A".into(),
            channels,
            time: 0.0,
        };
        assert!(c.apply(&a(vec![0.5, 0.25])));
        c.changes.clear();
        // NaN twice: no value taken and no change fired (NaN != NaN fired every time).
        for bad in [f64::NAN, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(!c.apply(&a(vec![0.75, bad])));
        }
        assert_eq!(c.changes, vec![]);
        assert_eq!(c.analogs["A.0"], 0.5);
        assert_eq!(c.analogs["A.1"], 0.25);
    }
}
