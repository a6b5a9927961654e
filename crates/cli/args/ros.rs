//! The ROS 2 command-line block, `--ros-args ... [--]`, as rcl reads it, for `iasm ros2`
//! and `iasm ros2-play`.
//!
//! A ROS user starts every node the same way (`ros2 run`, a launch file): the node's
//! namespace and name (`-r __ns:=/robot1`, `-r __node:=mapper`), topic remaps (`-r
//! from:=to`), parameters (`-p name:=value`, `--params-file FILE`). This module reads that
//! block and gives back what the commands need of it:
//!
//! - **Names.** A name is resolved as rcl resolves it ([`RosArgs::resolve`]): `/x` stays,
//!   `x` lies in the namespace, `~/x` under the node. A remap's two sides are resolved
//!   alike, and a name the node uses is replaced by the first remap whose left side is it
//!   ([`RosArgs::remapped`]).
//! - **Parameters.** The node's parameters are its flags: `-p method:=mvdr` is `--method
//!   mvdr`, `-p deflate:=true` is `--deflate` ([`to_flags`]), so that every setting with a
//!   flag is a parameter, checked by the same parser. A value is read as rcl reads it, as
//!   YAML (`true` a boolean, `8` an integer, `[0, 1]` a list, which a flag takes
//!   comma-separated). A parameters file is ROS 2's YAML format: a node's
//!   `ros__parameters` under its fully qualified name, its name alone, or a pattern (`/**`,
//!   `/*/iasm`); nested keys are dotted names. Files are read in order, then each `-p`;
//!   the last value of a name wins.
//! - **What is accepted and not used**: `--log-level`, `--enclave` (`-e`),
//!   `--disable-rosout-logs`, `--disable-stdout-logs`, `--enable-external-lib-logs`; said
//!   once on stderr. Anything else in the block is an error that names it.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use yaml_rust2::{Yaml, YamlLoader};

/// A parameter's value as ROS gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// `true` or `false`.
    Bool(bool),
    /// A whole number.
    Integer(i64),
    /// A number with a point or an exponent.
    Double(f64),
    /// Anything else.
    String(String),
    /// A list (`[0, 1, 2]`).
    Array(Vec<ParamValue>),
}

impl ParamValue {
    /// `text` read as rcl reads a `-p` value: as a YAML value (a string where it is none).
    #[must_use]
    pub fn parse(text: &str) -> Self {
        match YamlLoader::load_from_str(text) {
            Ok(docs) if docs.len() == 1 => {
                Self::from_yaml(&docs[0]).unwrap_or_else(|_| Self::String(text.to_owned()))
            }
            _ => Self::String(text.to_owned()),
        }
    }

    fn from_yaml(y: &Yaml) -> Result<Self> {
        Ok(match y {
            Yaml::Boolean(b) => Self::Bool(*b),
            Yaml::Integer(i) => Self::Integer(*i),
            Yaml::Real(r) => Self::Double(
                r.parse()
                    .map_err(|_| anyhow!("{r} is not a number ROS reads"))?,
            ),
            Yaml::String(s) => Self::String(s.clone()),
            Yaml::Array(a) => Self::Array(a.iter().map(Self::from_yaml).collect::<Result<_>>()?),
            other => bail!("{other:?} is not a parameter value (a scalar or a list)"),
        })
    }

    /// The value as a flag takes it: a list comma-separated.
    #[must_use]
    pub fn flag_text(&self) -> String {
        match self {
            Self::Bool(b) => b.to_string(),
            Self::Integer(i) => i.to_string(),
            Self::Double(d) => d.to_string(),
            Self::String(s) => s.clone(),
            Self::Array(a) => a.iter().map(Self::flag_text).collect::<Vec<_>>().join(","),
        }
    }
}

/// What a `--ros-args` block says.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RosArgs {
    /// `-r __ns:=` (absolute).
    pub namespace: Option<String>,
    /// `-r __node:=`.
    pub node_name: Option<String>,
    /// Every other `-r from:=to`, in order.
    pub remaps: Vec<(String, String)>,
    /// `--params-file`, in order.
    pub params_files: Vec<PathBuf>,
    /// `-p name:=value`, in order.
    pub params: Vec<(String, ParamValue)>,
    /// Options accepted and not used, as given.
    pub ignored: Vec<String>,
}

/// The marker that opens a ROS block, and the one that may close it.
pub const ROS_ARGS: &str = "--ros-args";

/// `argv` without its ROS blocks (each from `--ros-args` to `--` or the end), and the
/// tokens of those blocks, `None` where there is none.
///
/// # Errors
/// A token of a ROS block that is not UTF-8.
pub fn split(argv: Vec<OsString>) -> Result<(Vec<OsString>, Option<Vec<String>>)> {
    let mut rest = Vec::with_capacity(argv.len());
    let mut ros: Option<Vec<String>> = None;
    let mut inside = false;
    for a in argv {
        if a == ROS_ARGS {
            inside = true;
            ros.get_or_insert_with(Vec::new);
        } else if inside && a == "--" {
            inside = false;
        } else if inside {
            let s = a
                .into_string()
                .map_err(|a| anyhow!("--ros-args: {a:?} is not UTF-8"))?;
            ros.get_or_insert_with(Vec::new).push(s);
        } else {
            rest.push(a);
        }
    }
    Ok((rest, ros))
}

/// `name:=value`, split.
fn assignment<'a>(flag: &str, text: &'a str) -> Result<(&'a str, &'a str)> {
    text.split_once(":=")
        .filter(|(n, _)| !n.is_empty())
        .ok_or_else(|| anyhow!("--ros-args {flag} {text:?}: expected NAME:=VALUE"))
}

impl RosArgs {
    /// The tokens of a ROS block read.
    ///
    /// # Errors
    /// An option iasm does not know, a missing value, a malformed `NAME:=VALUE`, a
    /// namespace or node name that is not a ROS name.
    pub fn parse(tokens: &[String]) -> Result<Self> {
        let mut out = Self::default();
        let mut it = tokens.iter();
        while let Some(t) = it.next() {
            let mut value = |what: &str| {
                it.next()
                    .cloned()
                    .ok_or_else(|| anyhow!("--ros-args {t}: expected {what} after it"))
            };
            match t.as_str() {
                "-r" | "--remap" => {
                    let v = value("FROM:=TO")?;
                    let (from, to) = assignment(t, &v)?;
                    // A remap for one node (`node:from:=to`) applies here when it is ours;
                    // kept with its prefix and matched in `applies_to`.
                    match from {
                        "__ns" => {
                            check_name(to, true)?;
                            let ns = if to.starts_with('/') {
                                to.to_owned()
                            } else {
                                format!("/{to}")
                            };
                            out.namespace =
                                Some(ns.trim_end_matches('/').to_owned()).filter(|n| !n.is_empty());
                        }
                        "__node" | "__name" => {
                            check_name(to, false)?;
                            out.node_name = Some(to.to_owned());
                        }
                        _ => out.remaps.push((from.to_owned(), to.to_owned())),
                    }
                }
                "-p" | "--param" => {
                    let v = value("NAME:=VALUE")?;
                    let (n, val) = assignment(t, &v)?;
                    out.params.push((n.to_owned(), ParamValue::parse(val)));
                }
                "--params-file" => out.params_files.push(PathBuf::from(value("a FILE")?)),
                "--log-level" | "-e" | "--enclave" => {
                    let v = value("a value")?;
                    out.ignored.push(format!("{t} {v}"));
                }
                "--disable-rosout-logs"
                | "--disable-stdout-logs"
                | "--disable-external-lib-logs"
                | "--enable-rosout-logs"
                | "--enable-stdout-logs"
                | "--enable-external-lib-logs" => out.ignored.push(t.clone()),
                other => bail!(
                    "--ros-args: {other:?} is not an option iasm reads (it reads -r/--remap, \
                     -p/--param, --params-file, and accepts --log-level and --enclave)"
                ),
            }
        }
        Ok(out)
    }

    /// The namespace (`/` when none is given).
    #[must_use]
    pub fn namespace(&self) -> &str {
        self.namespace.as_deref().unwrap_or("/")
    }

    /// The node's fully qualified name, `default` its name unless `__node` renames it.
    #[must_use]
    pub fn fully_qualified(&self, default: &str) -> String {
        let name = self.node_name.as_deref().unwrap_or(default);
        match self.namespace.as_deref() {
            Some(ns) => format!("{ns}/{name}"),
            None => format!("/{name}"),
        }
    }

    /// `name` resolved as rcl resolves it for the node `node` (its name, not qualified):
    /// absolute names stay, `~` and `~/x` lie under the node, others in the namespace.
    #[must_use]
    pub fn resolve(&self, name: &str, node: &str) -> String {
        let ns = self.namespace.as_deref().unwrap_or("");
        let node = self.node_name.as_deref().unwrap_or(node);
        if name.starts_with('/') {
            name.to_owned()
        } else if name == "~" {
            format!("{ns}/{node}")
        } else if let Some(rest) = name.strip_prefix("~/") {
            format!("{ns}/{node}/{rest}")
        } else {
            format!("{ns}/{name}")
        }
    }

    /// The remaps that apply to the node `node` (a remap `other_node:from:=to` only to
    /// that node), both sides resolved.
    fn remaps_of<'a>(&'a self, node: &'a str) -> impl Iterator<Item = (String, String)> + 'a {
        let own = self.node_name.as_deref().unwrap_or(node);
        self.remaps.iter().filter_map(move |(from, to)| {
            let from = match from.split_once(':') {
                Some((n, f)) if n == own => f,
                Some(_) => return None,
                None => from.as_str(),
            };
            Some((self.resolve(from, node), self.resolve(to, node)))
        })
    }

    /// The topic the node `node` uses as `name`: resolved, then replaced by the first remap
    /// whose left side resolves to it.
    #[must_use]
    pub fn remapped(&self, name: &str, node: &str) -> String {
        let resolved = self.resolve(name, node);
        self.remaps_of(node)
            .find(|(from, _)| *from == resolved)
            .map_or(resolved, |(_, to)| to)
    }

    /// The name the node `node` knows the graph's topic `topic` by: the left side of the
    /// first remap whose right side resolves to it; else `topic` itself when it lies in the
    /// namespace (with none, every topic does); `None` for a topic outside the namespace
    /// that no remap names.
    #[must_use]
    pub fn own_name(&self, topic: &str, node: &str) -> Option<String> {
        if let Some((from, _)) = self.remaps_of(node).find(|(_, to)| to == topic) {
            return Some(from);
        }
        match &self.namespace {
            Some(ns) if !topic.starts_with(&format!("{ns}/")) => None,
            _ => Some(topic.to_owned()),
        }
    }

    /// Every parameter for the node whose fully qualified name is `fq`: the files' in
    /// order, then each `-p`; the last value of a name wins.
    ///
    /// # Errors
    /// A file that cannot be read or is not a ROS 2 parameters file.
    pub fn parameters(&self, fq: &str) -> Result<BTreeMap<String, ParamValue>> {
        let mut out = BTreeMap::new();
        for f in &self.params_files {
            out.extend(params_file(f, fq)?);
        }
        out.extend(self.params.iter().cloned());
        Ok(out)
    }
}

/// A namespace (`namespace`) or node name as ROS allows it: letters, digits and `_`, not
/// starting with a digit; a namespace may have `/` between tokens.
fn check_name(name: &str, namespace: bool) -> Result<()> {
    let tokens: Vec<&str> = if namespace {
        name.trim_matches('/').split('/').collect()
    } else {
        vec![name]
    };
    let ok = |t: &str| {
        !t.is_empty()
            && !t.starts_with(|c: char| c.is_ascii_digit())
            && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    if (namespace && name.trim_matches('/').is_empty()) || tokens.into_iter().all(ok) {
        Ok(())
    } else {
        bail!(
            "--ros-args: {name:?} is not a ROS {}: letters, digits and _, not starting with a digit",
            if namespace { "namespace" } else { "node name" }
        )
    }
}

/// Whether the node pattern of a parameters file (`/robot1/iasm`, `iasm`, `/**`,
/// `/*/iasm`, `/robot1/**`) names the node `fq`.
fn pattern_matches(pattern: &str, fq: &str) -> bool {
    fn m(p: &[&str], n: &[&str]) -> bool {
        match (p.first(), n.first()) {
            (None, None) => true,
            (Some(&"**"), _) => m(&p[1..], n) || (!n.is_empty() && m(p, &n[1..])),
            (Some(&"*"), Some(_)) => m(&p[1..], &n[1..]),
            (Some(a), Some(b)) if a == b => m(&p[1..], &n[1..]),
            _ => false,
        }
    }
    let p = pattern.trim_start_matches('/');
    let p: Vec<&str> = p.split('/').collect();
    let n: Vec<&str> = fq.trim_start_matches('/').split('/').collect();
    // A relative pattern (`iasm`) names the node in the root namespace, as rcl reads it.
    m(&p, &n)
}

/// The parameters that a ROS 2 parameters file gives the node `fq`, in file order.
fn params_file(path: &Path, fq: &str) -> Result<Vec<(String, ParamValue)>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--params-file {}", path.display()))?;
    let docs = YamlLoader::load_from_str(&text)
        .map_err(|e| anyhow!("--params-file {}: not YAML: {e}", path.display()))?;
    let mut out = Vec::new();
    for doc in &docs {
        let Yaml::Hash(nodes) = doc else {
            bail!(
                "--params-file {}: expected a map of node names to ros__parameters",
                path.display()
            );
        };
        for (node, body) in nodes {
            let Some(pattern) = node.as_str() else {
                bail!(
                    "--params-file {}: a node name {node:?} that is not a string",
                    path.display()
                );
            };
            if !pattern_matches(pattern, fq) {
                continue;
            }
            let params = body["ros__parameters"].as_hash().ok_or_else(|| {
                anyhow!(
                    "--params-file {}: {pattern}: expected ros__parameters under it",
                    path.display()
                )
            })?;
            flatten("", params, &mut out)
                .with_context(|| format!("--params-file {}: {pattern}", path.display()))?;
        }
    }
    Ok(out)
}

/// `hash`'s parameters, nested keys joined by dots under `prefix`.
fn flatten(
    prefix: &str,
    hash: &yaml_rust2::yaml::Hash,
    out: &mut Vec<(String, ParamValue)>,
) -> Result<()> {
    for (k, v) in hash {
        let key = match k {
            Yaml::String(s) => s.clone(),
            Yaml::Integer(i) => i.to_string(),
            other => bail!("a parameter name {other:?} that is not a string"),
        };
        let name = if prefix.is_empty() {
            key
        } else {
            format!("{prefix}.{key}")
        };
        match v {
            Yaml::Hash(h) => flatten(&name, h, out)?,
            v => out.push((
                name.clone(),
                ParamValue::from_yaml(v).with_context(|| format!("parameter {name}"))?,
            )),
        }
    }
    Ok(())
}

/// The flag of `cmd` that the parameter `name` sets (`still_radius` is `--still-radius`).
#[must_use]
pub fn flag_of<'a>(cmd: &'a clap::Command, name: &str) -> Option<&'a clap::Arg> {
    let long = name.replace('_', "-");
    cmd.get_arguments()
        .find(|a| a.get_long() == Some(long.as_str()) && !a.is_positional())
}

/// Whether `arg` is a switch (`--deflate`), which a boolean parameter sets.
#[must_use]
pub fn is_switch(arg: &clap::Arg) -> bool {
    matches!(arg.get_action(), clap::ArgAction::SetTrue)
}

/// The flags that `params` set on the command `cmd` (a subcommand of `iasm`).
///
/// # Errors
/// A parameter that is no flag of `cmd` (with the list of those that are), or a
/// switch given a value that is not a boolean.
pub fn to_flags(
    params: &BTreeMap<String, ParamValue>,
    cmd: &clap::Command,
) -> Result<Vec<OsString>> {
    let mut out = Vec::new();
    for (name, value) in params {
        let Some(arg) = flag_of(cmd, name) else {
            let names: Vec<String> = cmd
                .get_arguments()
                .filter_map(clap::Arg::get_long)
                .filter(|l| *l != "help" && *l != "version")
                .map(|l| l.replace('-', "_"))
                .collect();
            bail!(
                "parameter {name}: iasm {} has no such setting (its parameters: {})",
                cmd.get_name(),
                names.join(", ")
            );
        };
        let long = arg.get_long().expect("found by its long name");
        if is_switch(arg) {
            match value {
                ParamValue::Bool(true) => out.push(format!("--{long}").into()),
                ParamValue::Bool(false) => {}
                other => bail!("parameter {name}: a boolean, not {}", other.flag_text()),
            }
        } else {
            out.push(format!("--{long}={}", value.flag_text()).into());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<String> {
        s.split_whitespace().map(str::to_owned).collect()
    }

    #[test]
    fn a_ros_block_is_split_from_the_command_line_at_its_markers() {
        let argv: Vec<OsString> =
            toks("iasm ros2 --seed 5 --ros-args -r __ns:=/r1 -- --out m.json")
                .into_iter()
                .map(OsString::from)
                .collect();
        let (rest, ros) = split(argv).unwrap();
        assert_eq!(rest, ["iasm", "ros2", "--seed", "5", "--out", "m.json"]);
        assert_eq!(ros.unwrap(), ["-r", "__ns:=/r1"]);
        let (_, none) = split(vec!["iasm".into(), "map".into()]).unwrap();
        assert_eq!(none, None);
    }

    #[test]
    fn names_resolve_and_remap_as_rcl_resolves_them() {
        let r = RosArgs::parse(&toks(
            "-r __ns:=/robot1 -r __node:=mapper -r audio:=mic/raw -r /map:=/building/map \
             -r other:odom:=/nowhere -r mapper:odom:=wheel_odom",
        ))
        .unwrap();
        assert_eq!(r.fully_qualified("iasm"), "/robot1/mapper");
        assert_eq!(r.resolve("iasm/sources", "iasm"), "/robot1/iasm/sources");
        assert_eq!(r.resolve("~/save_map", "iasm"), "/robot1/mapper/save_map");
        assert_eq!(r.resolve("/tf", "iasm"), "/tf");
        assert_eq!(r.remapped("audio", "iasm"), "/robot1/mic/raw");
        assert_eq!(r.remapped("/robot1/audio", "iasm"), "/robot1/mic/raw");
        assert_eq!(r.remapped("/map", "iasm"), "/building/map");
        // A remap for another node is not ours; one for ours is.
        assert_eq!(r.remapped("odom", "iasm"), "/robot1/wheel_odom");
        assert_eq!(r.remapped("pose", "iasm"), "/robot1/pose");
        // The graph's topics by the node's own names: a remap's target by its source, a
        // topic of the namespace by itself, another robot's by none.
        assert_eq!(
            r.own_name("/robot1/mic/raw", "iasm").as_deref(),
            Some("/robot1/audio")
        );
        assert_eq!(r.own_name("/building/map", "iasm").as_deref(), Some("/map"));
        assert_eq!(
            r.own_name("/robot1/odom", "iasm").as_deref(),
            Some("/robot1/odom")
        );
        assert_eq!(r.own_name("/robot2/audio", "iasm"), None);
        assert_eq!(
            RosArgs::default()
                .own_name("/robot2/audio", "iasm")
                .as_deref(),
            Some("/robot2/audio")
        );
        // No namespace: the root.
        let root = RosArgs::default();
        assert_eq!(root.resolve("iasm/sources", "iasm"), "/iasm/sources");
        assert_eq!(root.fully_qualified("iasm"), "/iasm");
    }

    #[test]
    fn parameter_values_are_read_as_yaml_as_rcl_reads_them() {
        assert_eq!(ParamValue::parse("true"), ParamValue::Bool(true));
        assert_eq!(ParamValue::parse("8"), ParamValue::Integer(8));
        assert_eq!(ParamValue::parse("0.25"), ParamValue::Double(0.25));
        assert_eq!(ParamValue::parse("mvdr"), ParamValue::String("mvdr".into()));
        assert_eq!(ParamValue::parse("'8'"), ParamValue::String("8".into()));
        let list = ParamValue::parse("[0, 2, 4]");
        assert_eq!(list.flag_text(), "0,2,4");
    }

    #[test]
    fn what_the_block_does_not_hold_is_refused_by_name() {
        for bad in [
            "-x",
            "-r",
            "-r nocolon",
            "-p :=3",
            "-r __ns:=/9lives",
            "-r __node:=a/b",
        ] {
            let e = RosArgs::parse(&toks(bad)).unwrap_err().to_string();
            assert!(e.contains("--ros-args"), "{bad}: {e}");
        }
        let ok = RosArgs::parse(&toks("--log-level debug -e /x --disable-rosout-logs")).unwrap();
        assert_eq!(ok.ignored.len(), 3);
    }

    #[test]
    fn a_parameters_file_gives_the_node_its_own_and_the_patterns_values() {
        let dir = std::env::temp_dir().join(format!("iasm-params-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("p.yaml");
        std::fs::write(
            &f,
            "/**:\n  ros__parameters:\n    seed: 1\n    method: gcc-phat\n\
             /robot1/mapper:\n  ros__parameters:\n    method: mvdr\n    channels: [0, 1, 2]\n\
             \x20   nested:\n      depth: 2\n\
             /robot2/mapper:\n  ros__parameters:\n    seed: 99\n",
        )
        .unwrap();
        let r = RosArgs::parse(&[
            "--params-file".into(),
            f.display().to_string(),
            "-p".into(),
            "seed:=7".into(),
        ])
        .unwrap();
        let p = r.parameters("/robot1/mapper").unwrap();
        assert_eq!(p["method"], ParamValue::String("mvdr".into()));
        assert_eq!(p["channels"].flag_text(), "0,1,2");
        assert_eq!(p["nested.depth"], ParamValue::Integer(2));
        // -p comes after the files.
        assert_eq!(p["seed"], ParamValue::Integer(7));
        let other = r.parameters("/iasm").unwrap();
        assert_eq!(other["method"], ParamValue::String("gcc-phat".into()));
        assert!(!other.contains_key("channels"));
        std::fs::write(&f, "- a list\n").unwrap();
        let e = format!("{:#}", r.parameters("/iasm").unwrap_err());
        assert!(e.contains("p.yaml") && e.contains("ros__parameters"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn node_patterns_match_as_ros_matches_them() {
        assert!(pattern_matches("/**", "/robot1/iasm"));
        assert!(pattern_matches("/*/iasm", "/robot1/iasm"));
        assert!(!pattern_matches("/*/iasm", "/a/b/iasm"));
        assert!(pattern_matches("/**/iasm", "/a/b/iasm"));
        assert!(pattern_matches("iasm", "/iasm"));
        assert!(!pattern_matches("iasm", "/robot1/iasm"));
        assert!(pattern_matches("/robot1/**", "/robot1/iasm"));
    }

    #[test]
    fn parameters_become_the_flags_of_the_command() {
        use clap::{Arg, ArgAction, Command};
        let cmd = Command::new("ros2")
            .arg(Arg::new("method").long("method"))
            .arg(Arg::new("still_radius").long("still-radius"))
            .arg(
                Arg::new("deflate")
                    .long("deflate")
                    .action(ArgAction::SetTrue),
            )
            .arg(
                Arg::new("no_deflate")
                    .long("no-deflate")
                    .action(ArgAction::SetTrue),
            );
        let mut p = BTreeMap::new();
        p.insert("method".to_owned(), ParamValue::String("mvdr".into()));
        p.insert("still_radius".to_owned(), ParamValue::Double(0.1));
        p.insert("deflate".to_owned(), ParamValue::Bool(true));
        p.insert("no_deflate".to_owned(), ParamValue::Bool(false));
        let flags = to_flags(&p, &cmd).unwrap();
        assert_eq!(flags, ["--deflate", "--method=mvdr", "--still-radius=0.1"]);
        p.insert("fmin".to_owned(), ParamValue::Integer(300));
        let e = to_flags(&p, &cmd).unwrap_err().to_string();
        assert!(e.contains("fmin") && e.contains("still_radius"), "{e}");
        p.remove("fmin");
        p.insert("deflate".to_owned(), ParamValue::Integer(1));
        assert!(
            to_flags(&p, &cmd)
                .unwrap_err()
                .to_string()
                .contains("boolean")
        );
    }
}
