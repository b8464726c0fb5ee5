//! Paths, action sets, actions, suggested bindings, action states and haptics.

use crate::api::{enumerate_string, enumerate_values, get_str, input, out_ptr, output, run, Event, Instance};
use crate::profiles::{combine, ActionKind, Hand, Input, Profile, Reading, Source, TOP_LEVEL_PATHS};
use crate::state::{refuse, Refusal};
use openxr_sys as xr;
use serde_json::json;
use std::collections::HashMap;
use std::ffi::{c_char, CStr};

pub struct ActionSet {
    pub name: String,
    pub localized: String,
    pub attached: bool,
}

pub struct Action {
    pub set: u64,
    pub name: String,
    pub localized: String,
    pub kind: ActionKind,
    /// Subaction path ids.
    pub subactions: Vec<u64>,
}

/// An action's value as of the last xrSyncActions, for one subaction path (0: all).
#[derive(Clone, Copy, Default)]
struct Synced {
    reading: Option<Reading>,
    changed: bool,
    last_change: i64,
}

/// A session's attached action sets and their resolved bindings.
#[derive(Default)]
pub struct SessionActions {
    attached: Option<Vec<u64>>,
    profile: Option<&'static Profile>,
    bindings: HashMap<u64, Vec<Source>>,
    /// The path ids of /user/hand/left and /user/hand/right.
    hand_paths: [u64; 2],
    synced: HashMap<(u64, u64), Synced>,
}

impl SessionActions {
    fn sources(&self, action: u64, sub: u64) -> impl Iterator<Item = Source> + '_ {
        self.bindings
            .get(&action)
            .into_iter()
            .flatten()
            .copied()
            .filter(move |s| sub == 0 || self.hand_paths[s.hand.index()] == sub)
    }

    /// The source an action space follows: the first pose source, if the action is active.
    pub fn pose_source(&self, action: u64, sub: u64) -> Option<Source> {
        self.synced.get(&(action, sub))?.reading?;
        self.sources(action, sub).find(|s| matches!(s.input, Input::GripPose | Input::AimPose))
    }
}

fn kind_of(t: xr::ActionType) -> Option<ActionKind> {
    Some(match t {
        xr::ActionType::BOOLEAN_INPUT => ActionKind::Boolean,
        xr::ActionType::FLOAT_INPUT => ActionKind::Float,
        xr::ActionType::VECTOR2F_INPUT => ActionKind::Vector2,
        xr::ActionType::POSE_INPUT => ActionKind::Pose,
        xr::ActionType::VIBRATION_OUTPUT => ActionKind::Vibration,
        _ => return None,
    })
}

/// Path syntax (the specification's well-formed path rules).
pub fn check_path_syntax(s: &str) -> Result<(), String> {
    if s.len() >= xr::MAX_PATH_LENGTH {
        return Err(format!("path {s:?} is too long"));
    }
    let Some(rest) = s.strip_prefix('/') else { return Err(format!("path {s:?} does not start with /")) };
    for part in rest.split('/') {
        if part.is_empty() || part == "." || part == ".." {
            return Err(format!("path {s:?} has an empty, . or .. component"));
        }
        if !part.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b"-_.".contains(&b)) {
            return Err(format!("path {s:?} has characters other than a-z 0-9 - _ ."));
        }
    }
    Ok(())
}

fn check_name(name: &str, what: &str) -> Result<(), Refusal> {
    if name.is_empty()
        || !name.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b"-_.".contains(&b))
    {
        return refuse(xr::Result::ERROR_NAME_INVALID, format!("{what} {name:?} is not a well-formed name"));
    }
    Ok(())
}

pub(crate) unsafe extern "system" fn string_to_path(
    instance: xr::Instance,
    s: *const c_char,
    out: *mut xr::Path,
) -> xr::Result {
    run("xrStringToPath", |inst| {
        inst.check(instance)?;
        if s.is_null() {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "pathString is null");
        }
        out_ptr(out, "the path output")?;
        let s = CStr::from_ptr(s).to_string_lossy().into_owned();
        check_path_syntax(&s)
            .map_err(|why| Refusal { result: xr::Result::ERROR_PATH_FORMAT_INVALID, why })?;
        *out = inst.intern(&s);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn path_to_string(
    instance: xr::Instance,
    path: xr::Path,
    capacity: u32,
    count: *mut u32,
    buffer: *mut c_char,
) -> xr::Result {
    run("xrPathToString", |inst| {
        inst.check(instance)?;
        let s = inst.path_string(path)?.to_string();
        enumerate_string(capacity, count, buffer, &s)
    })
}

pub(crate) unsafe extern "system" fn create_action_set(
    instance: xr::Instance,
    info: *const xr::ActionSetCreateInfo,
    out: *mut xr::ActionSet,
) -> xr::Result {
    run("xrCreateActionSet", |inst| {
        inst.check(instance)?;
        let info = input(info, xr::StructureType::ACTION_SET_CREATE_INFO, "XrActionSetCreateInfo")?;
        out_ptr(out, "the action set output")?;
        let name = get_str(&info.action_set_name)?;
        let localized = get_str(&info.localized_action_set_name)?;
        check_name(&name, "actionSetName")?;
        if localized.is_empty() {
            return refuse(xr::Result::ERROR_LOCALIZED_NAME_INVALID, "localizedActionSetName is empty");
        }
        if inst.action_sets.values().any(|s| s.name == name) {
            return refuse(
                xr::Result::ERROR_NAME_DUPLICATED,
                format!("an action set is already named {name:?}"),
            );
        }
        if inst.action_sets.values().any(|s| s.localized == localized) {
            return refuse(
                xr::Result::ERROR_LOCALIZED_NAME_DUPLICATED,
                format!("an action set is already called {localized:?}"),
            );
        }
        let handle = crate::api::new_handle();
        inst.action_sets.insert(handle, ActionSet { name, localized, attached: false });
        *out = xr::ActionSet::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_action_set(set: xr::ActionSet) -> xr::Result {
    run("xrDestroyActionSet", |inst| {
        if inst.action_sets.remove(&set.into_raw()).is_none() {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("XrActionSet {:#x} is not a live action set", set.into_raw()),
            );
        }
        inst.actions.retain(|_, a| a.set != set.into_raw());
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn create_action(
    set: xr::ActionSet,
    info: *const xr::ActionCreateInfo,
    out: *mut xr::Action,
) -> xr::Result {
    run("xrCreateAction", |inst| {
        if inst.lost {
            return refuse(xr::Result::ERROR_INSTANCE_LOST, "the instance was lost; destroy it");
        }
        let Some(s) = inst.action_sets.get(&set.into_raw()) else {
            return refuse(
                xr::Result::ERROR_HANDLE_INVALID,
                format!("XrActionSet {:#x} is not a live action set", set.into_raw()),
            );
        };
        let info = input(info, xr::StructureType::ACTION_CREATE_INFO, "XrActionCreateInfo")?;
        out_ptr(out, "the action output")?;
        if s.attached {
            return refuse(
                xr::Result::ERROR_ACTIONSETS_ALREADY_ATTACHED,
                format!("action set {:?} is attached to a session", s.name),
            );
        }
        let name = get_str(&info.action_name)?;
        let localized = get_str(&info.localized_action_name)?;
        check_name(&name, "actionName")?;
        if localized.is_empty() {
            return refuse(xr::Result::ERROR_LOCALIZED_NAME_INVALID, "localizedActionName is empty");
        }
        let siblings = || inst.actions.values().filter(|a| a.set == set.into_raw());
        if siblings().any(|a| a.name == name) {
            return refuse(
                xr::Result::ERROR_NAME_DUPLICATED,
                format!("the set already has an action named {name:?}"),
            );
        }
        if siblings().any(|a| a.localized == localized) {
            return refuse(
                xr::Result::ERROR_LOCALIZED_NAME_DUPLICATED,
                format!("the set already has an action called {localized:?}"),
            );
        }
        let Some(kind) = kind_of(info.action_type) else {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("actionType {:?} is not an action type", info.action_type),
            );
        };
        let mut subactions = Vec::new();
        for i in 0..info.count_subaction_paths as usize {
            let p = *info.subaction_paths.add(i);
            let s = inst.path_string(p)?;
            if !TOP_LEVEL_PATHS.contains(&s) {
                return refuse(
                    xr::Result::ERROR_PATH_UNSUPPORTED,
                    format!("subaction path {s} is not a top-level user path"),
                );
            }
            if subactions.contains(&p.into_raw()) {
                return refuse(
                    xr::Result::ERROR_PATH_UNSUPPORTED,
                    format!("subaction path {s} is listed twice"),
                );
            }
            subactions.push(p.into_raw());
        }
        let handle = crate::api::new_handle();
        inst.actions.insert(handle, Action { set: set.into_raw(), name, localized, kind, subactions });
        *out = xr::Action::from_raw(handle);
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn destroy_action(action: xr::Action) -> xr::Result {
    run("xrDestroyAction", |inst| match inst.actions.remove(&action.into_raw()) {
        Some(_) => Ok(xr::Result::SUCCESS),
        None => refuse(
            xr::Result::ERROR_HANDLE_INVALID,
            format!("XrAction {:#x} is not a live action", action.into_raw()),
        ),
    })
}

fn action(inst: &Instance, a: xr::Action) -> Result<&Action, Refusal> {
    inst.actions.get(&a.into_raw()).ok_or_else(|| Refusal {
        result: xr::Result::ERROR_HANDLE_INVALID,
        why: format!("XrAction {:#x} is not a live action", a.into_raw()),
    })
}

pub(crate) unsafe extern "system" fn suggest_interaction_profile_bindings(
    instance: xr::Instance,
    info: *const xr::InteractionProfileSuggestedBinding,
) -> xr::Result {
    run("xrSuggestInteractionProfileBindings", |inst| {
        inst.check(instance)?;
        let info = input(
            info,
            xr::StructureType::INTERACTION_PROFILE_SUGGESTED_BINDING,
            "XrInteractionProfileSuggestedBinding",
        )?;
        let profile_path = inst.path_string(info.interaction_profile)?;
        let Some(profile) = Profile::find(profile_path) else {
            return refuse(
                xr::Result::ERROR_PATH_UNSUPPORTED,
                format!("interaction profile {profile_path} is not simulated"),
            );
        };
        if profile.by_extension && !inst.profile_extensions.contains(&profile.path) {
            return refuse(
                xr::Result::ERROR_PATH_UNSUPPORTED,
                format!("interaction profile {profile_path} needs its extension enabled"),
            );
        }
        if info.count_suggested_bindings == 0 || info.suggested_bindings.is_null() {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "no suggested bindings");
        }
        let mut list = Vec::new();
        for i in 0..info.count_suggested_bindings as usize {
            let b = *info.suggested_bindings.add(i);
            let a = action(inst, b.action)?;
            if inst.action_sets.get(&a.set).is_some_and(|s| s.attached) {
                return refuse(
                    xr::Result::ERROR_ACTIONSETS_ALREADY_ATTACHED,
                    format!("action {:?}'s set is already attached", a.name),
                );
            }
            let path = inst.path_string(b.binding)?;
            if profile.lookup(path).is_none() {
                return refuse(
                    xr::Result::ERROR_PATH_UNSUPPORTED,
                    format!("{path} is not a path of {}", profile.path),
                );
            }
            list.push((b.action.into_raw(), path.to_string()));
        }
        inst.suggested.insert(profile.path, list);
        Ok(xr::Result::SUCCESS)
    })
}

const SIMPLE: &str = "/interaction_profiles/khr/simple_controller";

/// The profile the simulated controllers present for the application's suggestions: the
/// script's if suggested, else the simple controller (which every controller can emulate).
pub fn resolve_profile(
    script_profile: &str,
    suggested: &HashMap<&'static str, Vec<(u64, String)>>,
) -> Option<&'static Profile> {
    [script_profile, SIMPLE].into_iter().find(|p| suggested.contains_key(p)).and_then(Profile::find)
}

pub(crate) unsafe extern "system" fn attach_session_action_sets(
    session: xr::Session,
    info: *const xr::SessionActionSetsAttachInfo,
) -> xr::Result {
    run("xrAttachSessionActionSets", |inst| {
        let s = inst.session(session)?;
        if s.actions.attached.is_some() {
            return refuse(
                xr::Result::ERROR_ACTIONSETS_ALREADY_ATTACHED,
                "the session already has its action sets",
            );
        }
        let info =
            input(info, xr::StructureType::SESSION_ACTION_SETS_ATTACH_INFO, "XrSessionActionSetsAttachInfo")?;
        let mut sets = Vec::new();
        for i in 0..info.count_action_sets as usize {
            let h = (*info.action_sets.add(i)).into_raw();
            if !inst.action_sets.contains_key(&h) {
                return refuse(
                    xr::Result::ERROR_HANDLE_INVALID,
                    format!("XrActionSet {h:#x} is not a live action set"),
                );
            }
            sets.push(h);
        }
        for h in &sets {
            inst.action_sets.get_mut(h).expect("checked").attached = true;
        }
        let profile = resolve_profile(&inst.script.interaction_profile, &inst.suggested);
        let hand_paths = Hand::BOTH.map(|h| inst.intern(h.user_path()).into_raw());
        let mut bindings: HashMap<u64, Vec<Source>> = HashMap::new();
        if let Some(p) = profile {
            let rest = inst.script.sample(0.0).hands[0];
            for (a, path) in &inst.suggested[p.path] {
                let Some(act) = inst.actions.get(a).filter(|act| sets.contains(&act.set)) else { continue };
                let source = p.lookup(path).expect("checked when suggested");
                if source.input.read_as(&rest, act.kind).is_some() {
                    bindings.entry(*a).or_default().push(source);
                }
            }
        }
        let s = inst.session.as_mut().expect("checked");
        s.actions =
            SessionActions { attached: Some(sets), profile, bindings, hand_paths, synced: HashMap::new() };
        inst.log.write(json!({"kind": "interaction_profile", "profile": profile.map(|p| p.path)}));
        if profile.is_some() {
            inst.events.push_back(Event::ProfileChanged { session: session.into_raw() });
        }
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_current_interaction_profile(
    session: xr::Session,
    top: xr::Path,
    out: *mut xr::InteractionProfileState,
) -> xr::Result {
    run("xrGetCurrentInteractionProfile", |inst| {
        let s = inst.session(session)?;
        if s.actions.attached.is_none() {
            return refuse(
                xr::Result::ERROR_ACTIONSET_NOT_ATTACHED,
                "no action sets are attached to the session",
            );
        }
        let profile = s.actions.profile;
        let out = output(out, xr::StructureType::INTERACTION_PROFILE_STATE, "XrInteractionProfileState")?;
        let path = inst.path_string(top)?;
        if !TOP_LEVEL_PATHS.contains(&path) {
            return refuse(
                xr::Result::ERROR_PATH_UNSUPPORTED,
                format!("{path} is not a top-level user path"),
            );
        }
        out.interaction_profile = match (Hand::from_user_path(path), profile) {
            (Some(_), Some(p)) => inst.intern(p.path),
            _ => xr::Path::NULL,
        };
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn sync_actions(
    session: xr::Session,
    info: *const xr::ActionsSyncInfo,
) -> xr::Result {
    run("xrSyncActions", |inst| {
        let s = inst.session(session)?;
        let Some(attached) = s.actions.attached.clone() else {
            return refuse(
                xr::Result::ERROR_ACTIONSET_NOT_ATTACHED,
                "no action sets are attached to the session",
            );
        };
        let focused = s.lifecycle.focused();
        let info = input(info, xr::StructureType::ACTIONS_SYNC_INFO, "XrActionsSyncInfo")?;
        let mut active: Vec<(u64, u64)> = Vec::new();
        for i in 0..info.count_active_action_sets as usize {
            let a = *info.active_action_sets.add(i);
            if !attached.contains(&a.action_set.into_raw()) {
                return refuse(
                    xr::Result::ERROR_ACTIONSET_NOT_ATTACHED,
                    format!("XrActionSet {:#x} is not attached to the session", a.action_set.into_raw()),
                );
            }
            if a.subaction_path != xr::Path::NULL
                && !TOP_LEVEL_PATHS.contains(&inst.path_string(a.subaction_path)?)
            {
                return refuse(
                    xr::Result::ERROR_PATH_UNSUPPORTED,
                    "an active action set's subaction path is not a top-level user path",
                );
            }
            active.push((a.action_set.into_raw(), a.subaction_path.into_raw()));
        }
        let time = inst.frame_time(inst.current_frame() as f64);
        let sample = inst.script.sample(inst.current_frame() as f64);
        let actions: Vec<(u64, ActionKind, u64, Vec<u64>)> = inst
            .actions
            .iter()
            .filter(|(_, a)| attached.contains(&a.set))
            .map(|(&h, a)| (h, a.kind, a.set, a.subactions.clone()))
            .collect();
        let s = inst.session.as_mut().expect("checked");
        let sa = &mut s.actions;
        let mut synced = HashMap::new();
        for (h, kind, set, subs) in actions {
            for sub in std::iter::once(0).chain(subs) {
                let reading = if focused {
                    let sources: Vec<Source> = sa
                        .sources(h, sub)
                        .filter(|src| {
                            active.iter().any(|&(aset, asub)| {
                                aset == set && (asub == 0 || sa.hand_paths[src.hand.index()] == asub)
                            })
                        })
                        .collect();
                    combine(
                        sources
                            .iter()
                            .filter_map(|src| src.input.read_as(&sample.hands[src.hand.index()], kind)),
                    )
                } else {
                    None
                };
                let old = sa.synced.get(&(h, sub)).copied().unwrap_or_default();
                let changed = match (old.reading, reading) {
                    (Some(a), Some(b)) => a != b && !matches!(b, Reading::Pose(_)),
                    _ => false,
                };
                let last_change = if changed || (old.reading.is_none() && reading.is_some()) {
                    time
                } else {
                    old.last_change
                };
                synced.insert((h, sub), Synced { reading, changed, last_change });
            }
        }
        sa.synced = synced;
        Ok(if focused { xr::Result::SUCCESS } else { xr::Result::SESSION_NOT_FOCUSED })
    })
}

/// Checks an action for a state query or action space: live, attached to the session, of the
/// kind asked, with a subaction path it was created with.
pub fn check_action_of_kind(
    inst: &mut Instance,
    session: xr::Session,
    a: xr::Action,
    sub: xr::Path,
    kind: ActionKind,
    needs_attached: bool,
) -> Result<(), Refusal> {
    let act = action(inst, a)?;
    let attached = inst.session.as_ref().and_then(|s| s.actions.attached.as_ref());
    // An action space may be made before its set is attached (it locates once the set is
    // attached and synced); states and haptics need the set attached.
    if needs_attached && !attached.is_some_and(|sets| sets.contains(&act.set)) {
        return refuse(
            xr::Result::ERROR_ACTIONSET_NOT_ATTACHED,
            format!("action {:?}'s set is not attached to XrSession {:#x}", act.name, session.into_raw()),
        );
    }
    if act.kind != kind {
        return refuse(
            xr::Result::ERROR_ACTION_TYPE_MISMATCH,
            format!("action {:?} is {:?}, not {kind:?}", act.name, act.kind),
        );
    }
    if sub != xr::Path::NULL && !act.subactions.contains(&sub.into_raw()) {
        let name = act.name.clone();
        let p = inst.path_string(sub)?;
        return refuse(
            xr::Result::ERROR_PATH_UNSUPPORTED,
            format!("action {name:?} was not created with subaction path {p}"),
        );
    }
    Ok(())
}

/// The state of an action for `xrGetActionState*`.
unsafe fn state(
    inst: &mut Instance,
    session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    kind: ActionKind,
) -> Result<Synced, Refusal> {
    inst.session(session)?;
    let info = input(info, xr::StructureType::ACTION_STATE_GET_INFO, "XrActionStateGetInfo")?;
    check_action_of_kind(inst, session, info.action, info.subaction_path, kind, true)?;
    let s = inst.session.as_ref().expect("checked");
    Ok(s.actions
        .synced
        .get(&(info.action.into_raw(), info.subaction_path.into_raw()))
        .copied()
        .unwrap_or_default())
}

pub(crate) unsafe extern "system" fn get_action_state_boolean(
    session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateBoolean,
) -> xr::Result {
    run("xrGetActionStateBoolean", |inst| {
        let st = state(inst, session, info, ActionKind::Boolean)?;
        let out = output(out, xr::StructureType::ACTION_STATE_BOOLEAN, "XrActionStateBoolean")?;
        out.current_state = matches!(st.reading, Some(Reading::Bool(true))).into();
        out.changed_since_last_sync = st.changed.into();
        out.last_change_time = xr::Time::from_nanos(st.last_change);
        out.is_active = st.reading.is_some().into();
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_action_state_float(
    session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateFloat,
) -> xr::Result {
    run("xrGetActionStateFloat", |inst| {
        let st = state(inst, session, info, ActionKind::Float)?;
        let out = output(out, xr::StructureType::ACTION_STATE_FLOAT, "XrActionStateFloat")?;
        out.current_state = match st.reading {
            Some(Reading::Float(f)) => f,
            _ => 0.0,
        };
        out.changed_since_last_sync = st.changed.into();
        out.last_change_time = xr::Time::from_nanos(st.last_change);
        out.is_active = st.reading.is_some().into();
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_action_state_vector2f(
    session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStateVector2f,
) -> xr::Result {
    run("xrGetActionStateVector2f", |inst| {
        let st = state(inst, session, info, ActionKind::Vector2)?;
        let out = output(out, xr::StructureType::ACTION_STATE_VECTOR2F, "XrActionStateVector2f")?;
        let [x, y] = match st.reading {
            Some(Reading::Vector2(v)) => v,
            _ => [0.0, 0.0],
        };
        out.current_state = xr::Vector2f { x, y };
        out.changed_since_last_sync = st.changed.into();
        out.last_change_time = xr::Time::from_nanos(st.last_change);
        out.is_active = st.reading.is_some().into();
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn get_action_state_pose(
    session: xr::Session,
    info: *const xr::ActionStateGetInfo,
    out: *mut xr::ActionStatePose,
) -> xr::Result {
    run("xrGetActionStatePose", |inst| {
        let st = state(inst, session, info, ActionKind::Pose)?;
        let out = output(out, xr::StructureType::ACTION_STATE_POSE, "XrActionStatePose")?;
        out.is_active = st.reading.is_some().into();
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn enumerate_bound_sources_for_action(
    session: xr::Session,
    info: *const xr::BoundSourcesForActionEnumerateInfo,
    capacity: u32,
    count: *mut u32,
    sources: *mut xr::Path,
) -> xr::Result {
    run("xrEnumerateBoundSourcesForAction", |inst| {
        inst.session(session)?;
        let info = input(
            info,
            xr::StructureType::BOUND_SOURCES_FOR_ACTION_ENUMERATE_INFO,
            "XrBoundSourcesForActionEnumerateInfo",
        )?;
        let kind = action(inst, info.action)?.kind;
        check_action_of_kind(inst, session, info.action, xr::Path::NULL, kind, true)?;
        let s = inst.session.as_ref().expect("checked");
        let Some(profile) = s.actions.profile else { return enumerate_values(capacity, count, sources, &[]) };
        let bound: Vec<Source> = s.actions.sources(info.action.into_raw(), 0).collect();
        let paths: Vec<String> = profile
            .all_paths()
            .into_iter()
            .filter(|p| profile.lookup(p).is_some_and(|src| bound.contains(&src)))
            .collect();
        let ids: Vec<xr::Path> = paths.iter().map(|p| inst.intern(p)).collect();
        enumerate_values(capacity, count, sources, &ids)
    })
}

pub(crate) unsafe extern "system" fn get_input_source_localized_name(
    session: xr::Session,
    info: *const xr::InputSourceLocalizedNameGetInfo,
    capacity: u32,
    count: *mut u32,
    buffer: *mut c_char,
) -> xr::Result {
    run("xrGetInputSourceLocalizedName", |inst| {
        inst.session(session)?;
        let info = input(
            info,
            xr::StructureType::INPUT_SOURCE_LOCALIZED_NAME_GET_INFO,
            "XrInputSourceLocalizedNameGetInfo",
        )?;
        if info.which_components.is_empty() {
            return refuse(xr::Result::ERROR_VALIDATION_FAILURE, "whichComponents is 0");
        }
        let path = inst.path_string(info.source_path)?.to_string();
        let hand = Hand::BOTH.into_iter().find(|h| path.starts_with(h.user_path()));
        let Some(hand) = hand else {
            return refuse(
                xr::Result::ERROR_PATH_UNSUPPORTED,
                format!("{path} is not an input source of the simulated controllers"),
            );
        };
        let mut parts = Vec::new();
        if info.which_components.contains(xr::InputSourceLocalizedNameFlags::USER_PATH) {
            parts.push(format!("{} hand", if hand == Hand::Left { "Left" } else { "Right" }));
        }
        if info.which_components.contains(xr::InputSourceLocalizedNameFlags::INTERACTION_PROFILE) {
            let profile =
                inst.session.as_ref().and_then(|s| s.actions.profile).map_or("no controller", |p| p.path);
            parts.push(profile.rsplit('/').next().unwrap_or(profile).replace('_', " "));
        }
        if info.which_components.contains(xr::InputSourceLocalizedNameFlags::COMPONENT) {
            parts.push(path[hand.user_path().len()..].trim_start_matches("/input/").replace('/', " "));
        }
        enumerate_string(capacity, count, buffer, &parts.join(" "))
    })
}

/// The hands a haptic action reaches: those of its bound haptic outputs.
unsafe fn haptic_hands(
    inst: &mut Instance,
    session: xr::Session,
    info: *const xr::HapticActionInfo,
) -> Result<Option<Vec<Hand>>, Refusal> {
    let s = inst.session(session)?;
    let focused = s.lifecycle.focused();
    let info = input(info, xr::StructureType::HAPTIC_ACTION_INFO, "XrHapticActionInfo")?;
    check_action_of_kind(inst, session, info.action, info.subaction_path, ActionKind::Vibration, true)?;
    if !focused {
        return Ok(None);
    }
    let s = inst.session.as_ref().expect("checked");
    let mut hands: Vec<Hand> = s
        .actions
        .sources(info.action.into_raw(), info.subaction_path.into_raw())
        .map(|src| src.hand)
        .collect();
    hands.sort();
    hands.dedup();
    Ok(Some(hands))
}

pub(crate) unsafe extern "system" fn apply_haptic_feedback(
    session: xr::Session,
    info: *const xr::HapticActionInfo,
    feedback: *const xr::HapticBaseHeader,
) -> xr::Result {
    run("xrApplyHapticFeedback", |inst| {
        let hands = haptic_hands(inst, session, info)?;
        let v = input(
            feedback as *const xr::HapticVibration,
            xr::StructureType::HAPTIC_VIBRATION,
            "XrHapticVibration",
        )?;
        if !(0.0..=1.0).contains(&v.amplitude) || v.frequency < 0.0 || !v.frequency.is_finite() {
            return refuse(
                xr::Result::ERROR_VALIDATION_FAILURE,
                format!("amplitude {} (0 to 1) or frequency {} (≥ 0)", v.amplitude, v.frequency),
            );
        }
        let Some(hands) = hands else { return Ok(xr::Result::SESSION_NOT_FOCUSED) };
        let frame = inst.current_frame();
        for h in hands {
            inst.log.write(json!({"kind": "haptic", "frame": frame, "hand": h.name(), "amplitude": v.amplitude, "duration_ns": v.duration.as_nanos(), "frequency": v.frequency}));
        }
        Ok(xr::Result::SUCCESS)
    })
}

pub(crate) unsafe extern "system" fn stop_haptic_feedback(
    session: xr::Session,
    info: *const xr::HapticActionInfo,
) -> xr::Result {
    run("xrStopHapticFeedback", |inst| {
        let Some(hands) = haptic_hands(inst, session, info)? else {
            return Ok(xr::Result::SESSION_NOT_FOCUSED);
        };
        let frame = inst.current_frame();
        for h in hands {
            inst.log.write(json!({"kind": "haptic_stop", "frame": frame, "hand": h.name()}));
        }
        Ok(xr::Result::SUCCESS)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_syntax_follows_the_specification() {
        for good in ["/user/hand/left", "/interaction_profiles/khr/simple_controller", "/a.b-c_d/0"] {
            assert!(check_path_syntax(good).is_ok(), "{good}");
        }
        for bad in
            ["user/hand", "/user/hand/", "/user//hand", "/User/hand", "/user/./hand", "/user/hand left", ""]
        {
            assert!(check_path_syntax(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_script_profile_wins_and_the_simple_controller_is_the_fallback() {
        let touch = "/interaction_profiles/oculus/touch_controller";
        let mut suggested: HashMap<&'static str, Vec<(u64, String)>> = HashMap::new();
        assert!(resolve_profile(touch, &suggested).is_none());
        suggested.insert(SIMPLE, vec![]);
        assert_eq!(resolve_profile(touch, &suggested).map(|p| p.path), Some(SIMPLE));
        suggested.insert("/interaction_profiles/valve/index_controller", vec![]);
        assert_eq!(resolve_profile(touch, &suggested).map(|p| p.path), Some(SIMPLE));
        suggested.insert("/interaction_profiles/oculus/touch_controller", vec![]);
        assert_eq!(resolve_profile(touch, &suggested).map(|p| p.path), Some(touch));
    }
}
