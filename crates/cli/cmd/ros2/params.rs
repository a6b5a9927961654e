//! The node's parameters, services and clock.
//!
//! **Parameters.** Every flag of `iasm ros2` is a parameter of the node (`--still-radius`
//! is `still_radius`), declared with the value the node started with, typed as the flag
//! parses (a number of seconds a double, a count an integer, a switch a boolean, a name or
//! a path a string; a flag not given and without a default is declared unset). `ros2 param
//! list/get/set/describe` and `ros2 param dump` see them through the six `rcl_interfaces`
//! services that ros2-client serves. A set is checked as the command line is: the
//! parameters are made flags again and parsed, then the settings validated, and a refusal
//! goes back to `ros2 param set` with its reason. The settings (the SSL's and the
//! mapper's, `iasm map`'s flags) and the seed take effect at the next stop: the mapper is
//! rebuilt over the stops so far, whose DoAs are kept. The others (topics, the audio's
//! format, the stop rules, the outputs, the domain) are read when the node starts and a set
//! is refused, saying so.
//!
//! **Services** (`std_srvs/srv/Trigger`, so that `ros2 service call` needs no package of
//! ours): `~/save_map` writes the current map to `save_to` (a parameter), `~/get_map`
//! answers with the map's JSON, `~/clear_map` forgets every stop.
//!
//! **Clock.** With `use_sim_time` (a parameter that may change while the node runs) the
//! node's time is the last `/clock` message (`rosgraph_msgs/msg/Clock`, as `ros2 bag play
//! --clock` publishes it), zero before the first, as rclcpp's clock is; else the system
//! clock.

use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsString;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use anyhow::{Result, anyhow};
use clap::CommandFactory;
use ros2_client::ParameterValue;
use serde::{Deserialize, Serialize};

use crate::args::{Cli, Command, Ros2Args, SettingsArgs};

use super::{Reader, now_ns, qos, raw, reader};

/// The node's parameter table: name to value, as the store holds them.
type Table = BTreeMap<String, ParameterValue>;

/// The node's parameters: the table and which of them changed since the loop last looked.
pub(super) struct NodeParams {
    table: Arc<Mutex<Table>>,
    changed: Arc<AtomicBool>,
    live: Arc<BTreeSet<String>>,
}

/// The parameters that take effect at the next stop: the settings and the seed.
fn live_names() -> BTreeSet<String> {
    let cmd = <SettingsArgs as clap::Args>::augment_args(clap::Command::new("settings"));
    cmd.get_arguments()
        .filter_map(clap::Arg::get_long)
        .map(|l| l.replace('-', "_"))
        .chain(["seed".to_owned()])
        .collect()
}

/// A flag's value typed as the flag parses it.
fn typed(arg: &clap::Arg, text: &str) -> ParameterValue {
    use std::any::TypeId;
    let t = arg.get_value_parser().type_id();
    let is = |id: TypeId| t == id;
    if is(TypeId::of::<f64>()) || is(TypeId::of::<f32>()) {
        text.parse().map_or_else(
            |_| ParameterValue::String(text.to_owned()),
            ParameterValue::Double,
        )
    } else if [
        TypeId::of::<u8>(),
        TypeId::of::<u16>(),
        TypeId::of::<u32>(),
        TypeId::of::<u64>(),
        TypeId::of::<usize>(),
        TypeId::of::<i32>(),
        TypeId::of::<i64>(),
    ]
    .into_iter()
    .any(is)
    {
        text.parse().map_or_else(
            |_| ParameterValue::String(text.to_owned()),
            ParameterValue::Integer,
        )
    } else {
        ParameterValue::String(text.to_owned())
    }
}

/// The `ros2` subcommand's definition.
fn ros2_command() -> clap::Command {
    Cli::command()
        .find_subcommand("ros2")
        .expect("iasm has the ros2 subcommand")
        .clone()
}

/// `value` as a flag's text.
fn text(value: &ParameterValue) -> Option<String> {
    let join = |v: Vec<String>| v.join(",");
    Some(match value {
        ParameterValue::NotSet | ParameterValue::Boolean(_) => return None,
        ParameterValue::Integer(i) => i.to_string(),
        ParameterValue::Double(d) => d.to_string(),
        ParameterValue::String(s) => s.clone(),
        ParameterValue::IntegerArray(a) => join(a.iter().map(ToString::to_string).collect()),
        ParameterValue::DoubleArray(a) => join(a.iter().map(ToString::to_string).collect()),
        ParameterValue::StringArray(a) => join(a.clone()),
        ParameterValue::BooleanArray(a) => join(a.iter().map(ToString::to_string).collect()),
        ParameterValue::ByteArray(a) => join(a.iter().map(ToString::to_string).collect()),
    })
}

/// `iasm ros2` with the parameters of `table` as its flags, parsed.
fn parse(table: &Table) -> Result<Ros2Args, String> {
    let cmd = ros2_command();
    let mut argv: Vec<OsString> = vec!["iasm".into(), "ros2".into()];
    for (name, value) in table {
        let Some(arg) = crate::args::ros::flag_of(&cmd, name) else {
            continue;
        };
        let long = arg.get_long().expect("found by it");
        match value {
            ParameterValue::Boolean(true) => argv.push(format!("--{long}").into()),
            v => {
                // A default is left to the parser (given, it would count as set: a flag
                // that requires another would ask for it).
                let default = arg
                    .get_default_values()
                    .first()
                    .map(|d| d.to_string_lossy());
                if let Some(t) = text(v)
                    && default.as_deref() != Some(t.as_str())
                {
                    argv.push(format!("--{long}={t}").into());
                }
            }
        }
    }
    match <Cli as clap::Parser>::try_parse_from(argv) {
        Ok(Cli {
            command: Command::Ros2(a),
        }) => Ok(a),
        Ok(_) => Err("not the ros2 command".into()),
        Err(e) => Err(e.render().to_string().trim().to_owned()),
    }
}

impl NodeParams {
    /// The table of the command line `command_line` (`iasm ros2 ...`, every parameter of
    /// the ROS block as its flag).
    ///
    /// # Errors
    /// A command line that does not parse (it did, to start the node).
    pub fn new(command_line: &[OsString]) -> Result<Self> {
        let m = Cli::command()
            .try_get_matches_from(command_line)
            .map_err(|e| anyhow!("{e}"))?;
        let (_, sub) = m
            .subcommand()
            .ok_or_else(|| anyhow!("not the ros2 command"))?;
        let mut table = Table::new();
        for arg in ros2_command().get_arguments() {
            let Some(long) = arg.get_long() else { continue };
            if arg.is_positional() || long == "help" {
                continue;
            }
            let id = arg.get_id().as_str();
            let value = if crate::args::ros::is_switch(arg) {
                ParameterValue::Boolean(sub.get_flag(id))
            } else {
                match sub.get_raw(id).and_then(|mut v| v.next()) {
                    Some(v) => typed(arg, &v.to_string_lossy()),
                    None => ParameterValue::NotSet,
                }
            };
            table.insert(long.replace('-', "_"), value);
        }
        Ok(Self {
            table: Arc::new(Mutex::new(table)),
            changed: Arc::new(AtomicBool::new(false)),
            live: Arc::new(live_names()),
        })
    }

    /// The node's options: every parameter declared, a set checked as the command line
    /// is ([`NodeParams::validator`]) and recorded for the loop ([`NodeParams::set_action`]).
    pub fn node_options(&self) -> ros2_client::NodeOptions {
        let mut o = ros2_client::NodeOptions::new();
        for (name, value) in self.table.lock().expect("not poisoned").iter() {
            o = o.declare_parameter(name, value.clone());
        }
        o.parameter_validator(Box::new(self.validator()))
            .parameter_set_action(Box::new(self.set_action()))
    }

    /// Whether a parameter may be set to a value, and if not why: the same value, or a
    /// setting whose command line parses and whose settings validate.
    fn validator(
        &self,
    ) -> impl Fn(&str, &ParameterValue) -> Result<(), String> + Send + Sync + use<> {
        let (table, live) = (Arc::clone(&self.table), Arc::clone(&self.live));
        move |name: &str, value: &ParameterValue| {
            let t = table.lock().expect("not poisoned");
            if t.get(name) == Some(value) {
                return Ok(());
            }
            if !live.contains(name) {
                return Err(format!(
                    "{name} is read when the node starts: restart the node to change it \
                     (the settings and the seed take effect at the next stop)"
                ));
            }
            let mut next = t.clone();
            next.insert(name.to_owned(), value.clone());
            drop(t);
            let a = parse(&next)?;
            let s = a.settings.settings().map_err(|e| format!("{e:#}"))?;
            s.validate()
                .and_then(|()| s.mic_array().map(drop))
                .map_err(|e| format!("{name}: {e:#}"))
        }
    }

    /// A set value recorded, the loop told when it changed.
    fn set_action(
        &self,
    ) -> impl Fn(&str, &ParameterValue) -> Result<(), String> + Send + Sync + use<> {
        let (table, changed) = (Arc::clone(&self.table), Arc::clone(&self.changed));
        move |name: &str, value: &ParameterValue| {
            let mut t = table.lock().expect("not poisoned");
            if t.get(name) != Some(value) {
                t.insert(name.to_owned(), value.clone());
                changed.store(true, Ordering::SeqCst);
            }
            Ok(())
        }
    }

    /// The command parsed from the parameters as they are now, when one changed since the
    /// last call.
    pub fn take_changed(&self) -> Option<Result<Ros2Args>> {
        if !self.changed.swap(false, Ordering::SeqCst) {
            return None;
        }
        let t = self.table.lock().expect("not poisoned").clone();
        Some(parse(&t).map_err(|e| anyhow!(e)))
    }
}

/// `std_srvs/srv/Trigger`'s request: empty, which CDR writes as one byte.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TriggerRequest {
    /// The byte an empty message is written as.
    pub structure_needs_at_least_one_member: u8,
}
impl ros2_client::Message for TriggerRequest {}

/// `std_srvs/srv/Trigger`'s response.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TriggerResponse {
    /// Whether it was done.
    pub success: bool,
    /// What was done, or why not; `get_map`: the map's JSON.
    pub message: String,
}
impl ros2_client::Message for TriggerResponse {}

/// A Trigger server.
pub(super) type Trigger = ros2_client::Server<TriggerRequest, TriggerResponse>;

/// The services' QoS (rclcpp's default for services: reliable, volatile, keep last 10).
pub(super) fn service_qos() -> ros2_client::QosProfile {
    use ros2_client::qos::{Durability, History, WhenFull};
    ros2_client::QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

/// What a service asks of the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ask {
    /// `~/save_map`.
    Save,
    /// `~/get_map`.
    Get,
    /// `~/clear_map`.
    Clear,
}

/// The node's services.
pub(super) struct Services {
    servers: Vec<(Ask, Trigger)>,
}

impl Services {
    /// `~/save_map`, `~/get_map` and `~/clear_map` of the node `fq` (fully qualified).
    ///
    /// # Errors
    /// DDS that cannot make them.
    pub fn new(node: &mut ros2_client::Node, fq: &str) -> Result<Self> {
        let mut servers = Vec::new();
        for (ask, name) in [
            (Ask::Save, "save_map"),
            (Ask::Get, "get_map"),
            (Ask::Clear, "clear_map"),
        ] {
            let n = ros2_client::Name::new(fq, name).map_err(|e| anyhow!("{fq}/{name}: {e:?}"))?;
            let s = node
                .create_server::<TriggerRequest, TriggerResponse>(
                    ros2_client::ServiceMapping::Enhanced,
                    &n,
                    &ros2_client::ServiceTypeName::new("std_srvs", "Trigger"),
                    service_qos(),
                    service_qos(),
                )
                .map_err(|e| anyhow!("the service {fq}/{name}: {e:?}"))?;
            servers.push((ask, s));
        }
        Ok(Self { servers })
    }

    /// Answers every request waiting, `answer` saying what each did.
    pub fn serve(&mut self, mut answer: impl FnMut(Ask) -> TriggerResponse) {
        for (ask, s) in &self.servers {
            while let Ok(Some((id, _))) = s.receive_request() {
                let r = answer(*ask);
                if let Err(e) = s.send_response(id, r) {
                    eprintln!("warning: a response of {ask:?} not sent: {e:?}");
                }
            }
        }
    }
}

/// The node's time: the system's, or with `use_sim_time` the last `/clock`.
pub(super) struct Clock {
    reader: Reader,
    last_ns: i64,
}

impl Clock {
    /// A reader of `/clock`.
    ///
    /// # Errors
    /// DDS that cannot make it.
    pub fn new(dp: &rustdds::DomainParticipant, subscriber: &rustdds::Subscriber) -> Result<Self> {
        let names = super::dds_names("/clock", "rosgraph_msgs/msg/Clock");
        Ok(Self {
            reader: reader(dp, subscriber, names, qos(false, false, 1))?,
            last_ns: 0,
        })
    }

    /// Now (ns since the epoch): the last `/clock` received when `sim`, else the system's.
    pub fn now_ns(&mut self, sim: bool) -> i64 {
        while let Ok(Some(s)) = self.reader.take_next_sample() {
            // Clock: a builtin_interfaces/Time (int32 sec, uint32 nanosec) after the header.
            let b = &s.value().0;
            if let (Some(sec), Some(ns)) = (b.get(4..8), b.get(8..12)) {
                let sec = i32::from_le_bytes(sec.try_into().expect("4"));
                let ns = u32::from_le_bytes(ns.try_into().expect("4"));
                self.last_ns = iasm_ros::msg::Time { sec, nanosec: ns }.ns();
            }
        }
        if sim { self.last_ns } else { now_ns() }
    }
}

/// A `/clock` message at `ns` (CDR with its header).
pub(super) fn clock_message(ns: i64) -> raw::Cdr {
    let t = iasm_ros::msg::Time::from_ns(ns);
    let mut v = iasm_ros::cdr::CDR_LE.to_vec();
    v.extend_from_slice(&t.sec.to_le_bytes());
    v.extend_from_slice(&t.nanosec.to_le_bytes());
    raw::Cdr(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command_line(s: &str) -> Vec<OsString> {
        s.split_whitespace().map(OsString::from).collect()
    }

    #[test]
    fn every_flag_is_a_parameter_typed_as_its_flag_parses() {
        let p =
            NodeParams::new(&command_line("iasm ros2 --method mvdr --deflate --seed 3")).unwrap();
        let t = p.table.lock().unwrap().clone();
        assert_eq!(t["method"], ParameterValue::String("mvdr".into()));
        assert_eq!(t["deflate"], ParameterValue::Boolean(true));
        assert_eq!(t["no_deflate"], ParameterValue::Boolean(false));
        assert_eq!(t["seed"], ParameterValue::Integer(3));
        assert_eq!(
            t["still_radius"],
            ParameterValue::Double(bag::StopOptions::default().radius_m)
        );
        assert_eq!(t["num"], ParameterValue::NotSet);
        assert_eq!(t["node_name"], ParameterValue::String("iasm".into()));
        assert!(!t.contains_key("help"));
        // The table parses back to the command it came from.
        let a = parse(&t).unwrap();
        assert_eq!((a.seed, a.settings.deflate), (3, true));
        assert_eq!(a.settings.method, Some(ssl::Method::Mvdr));
    }

    #[test]
    fn a_set_is_checked_as_the_command_line_is_and_only_settings_change_live() {
        let p = NodeParams::new(&command_line("iasm ros2")).unwrap();
        let check = p.validator();
        let ok = |n: &str, v: ParameterValue| check(n, &v);
        assert_eq!(ok("method", ParameterValue::String("mvdr".into())), Ok(()));
        assert_eq!(ok("num", ParameterValue::Integer(6)), Ok(()));
        let e = ok("method", ParameterValue::String("nonesuch".into())).unwrap_err();
        assert!(e.contains("nonesuch"), "{e}");
        let e = ok("fmin", ParameterValue::Double(-5.0)).unwrap_err();
        assert!(e.contains("fmin") || e.contains("band"), "{e}");
        let e = ok("audio_topic", ParameterValue::String("/mic".into())).unwrap_err();
        assert!(e.contains("restart the node"), "{e}");
        // A value equal to today's is no change.
        assert_eq!(
            ok("node_name", ParameterValue::String("iasm".into())),
            Ok(())
        );
        let set = p.set_action();
        set("method", &ParameterValue::String("mvdr".into())).unwrap();
        let a = p.take_changed().unwrap().unwrap();
        assert_eq!(a.settings.method, Some(ssl::Method::Mvdr));
        assert!(p.take_changed().is_none());
    }
}
