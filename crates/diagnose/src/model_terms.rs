//! Reading and changing one term of one channel of a `SensorModel`, through `noise::Term`: the
//! term's level, shape and a copy at another level are the noise crate's (`ErrorTerm::level`,
//! `ErrorTerm::shape`, `Term::with_level`).

use noise::{BiasInstability, Channel, Effect, Flicker, OutputFilter, SensorModel, Term};

/// The term the model has for `effect` on channel `ch`, if it is in a form diagnose fits: one with
/// a level (`Term::level`). A Woodman random-walk bias instability is read as absent flicker.
pub fn fitted_term(model: &SensorModel, ch: Channel, effect: Effect) -> Option<&Term> {
    let term = model.axis(ch.sensor(), ch.axis()).term(effect)?;
    match term {
        Term::BiasInstability(BiasInstability::RandomWalk { .. }) => None,
        t => t.level().map(|_| t),
    }
}

/// The squared level of `term` (what its Allan variance is linear in); 0 without a term.
pub fn squared_level(term: Option<&Term>) -> f64 {
    term.and_then(Term::level).map_or(0.0, |(_, v)| v * v)
}

/// The output filter channel `ch` has, if any.
pub fn output_filter(model: &SensorModel, ch: Channel) -> Option<OutputFilter> {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis(sensor, axis).get::<OutputFilter>().copied()
}

/// Does channel `ch` model its bias instability as Woodman's random walk (TR-696 eq 9)?
pub fn has_random_walk_bias_instability(model: &SensorModel, ch: Channel) -> bool {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    matches!(
        model.axis(sensor, axis).get::<BiasInstability>(),
        Some(BiasInstability::RandomWalk { .. })
    )
}

/// The flicker band the model uses on channel `ch` (its own, or the noise crate's default), at
/// B = 1.
pub fn flicker_band(model: &SensorModel, ch: Channel) -> Flicker {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    match model.axis(sensor, axis).get::<BiasInstability>() {
        Some(BiasInstability::Flicker(f)) => f.with_level(1.0),
        _ => Flicker::with_b(1.0),
    }
    .expect("B = 1 is a valid level")
}

/// Put `term` on channel `ch`, in place of the term of its effect if there is one. The term is
/// valid by construction (its type's validating constructor made it).
pub fn set_term(model: &mut SensorModel, ch: Channel, term: Term) {
    model.axis_mut(ch.sensor(), ch.axis()).set_term(term);
}

/// Put back `previous` as channel `ch`'s term of `effect` (None: remove the effect).
pub fn restore_term(model: &mut SensorModel, ch: Channel, effect: Effect, previous: Option<Term>) {
    match previous {
        Some(t) => set_term(model, ch, t),
        None => clear_term(model, ch, effect),
    }
}

/// The term channel `ch` has for `effect` now, whatever its form (to restore it later).
pub fn current_term(model: &SensorModel, ch: Channel, effect: Effect) -> Option<Term> {
    model.axis(ch.sensor(), ch.axis()).term(effect).cloned()
}

/// Remove `effect` from channel `ch`.
pub fn clear_term(model: &mut SensorModel, ch: Channel, effect: Effect) {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis_mut(sensor, axis).remove(effect);
}
