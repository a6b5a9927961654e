//! `iasm ros2-call`: the node's parameters and services from a shell with no ROS installed
//! (where ROS is, `ros2 param` and `ros2 service call` do the same).

use std::time::{Duration, Instant};

use anyhow::{Result, anyhow, bail};
use ros2_client::rcl_interfaces::{
    GetParametersRequest, GetParametersResponse, ListParametersRequest, ListParametersResponse,
    SetParametersRequest, SetParametersResponse,
};
use ros2_client::{Message, Parameter, ParameterValue};

use crate::Outcome;
use crate::args::ros::ParamValue;
use crate::args::{Ros2CallArgs, Ros2CallWhat};

use super::params::{TriggerRequest, TriggerResponse, service_qos};

/// Calls the service `node`/`name` of type `pkg`/`ty` with `req`: sent again every second
/// until an answer comes (a request sent before discovery has matched the server is lost),
/// or `timeout` passes.
fn call<Q, R>(
    client_node: &mut ros2_client::Node,
    (node, name): (&str, &str),
    (pkg, ty): (&str, &str),
    req: &Q,
    timeout: Duration,
) -> Result<R>
where
    Q: Message + Clone + 'static,
    R: Message + 'static,
{
    let service =
        ros2_client::Name::new(node, name).map_err(|e| anyhow!("{node}/{name}: {e:?}"))?;
    let client = client_node
        .create_client::<Q, R>(
            ros2_client::ServiceMapping::Enhanced,
            &service,
            &ros2_client::ServiceTypeName::new(pkg, ty),
            service_qos(),
            service_qos(),
        )
        .map_err(|e| anyhow!("a client of {node}/{name}: {e:?}"))?;
    let t0 = Instant::now();
    let mut sent: Option<Instant> = None;
    loop {
        if sent.is_none_or(|s| s.elapsed() > Duration::from_secs(1)) {
            client
                .send_request(req.clone())
                .map_err(|e| anyhow!("calling {node}/{name}: {e:?}"))?;
            sent = Some(Instant::now());
        }
        if let Ok(Some((_, r))) = client.receive_response() {
            return Ok(r);
        }
        if t0.elapsed() > timeout {
            bail!(
                "no answer from {node}/{name} in {} s: is the node running, on this DDS domain?",
                timeout.as_secs_f64()
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A parameter's value as `ros2 param get` prints it.
fn shown(v: &ParameterValue) -> String {
    match v {
        ParameterValue::NotSet => "(not set)".to_owned(),
        ParameterValue::Boolean(b) => b.to_string(),
        ParameterValue::Integer(i) => i.to_string(),
        ParameterValue::Double(d) => format!("{d:?}"),
        ParameterValue::String(s) => s.clone(),
        other => format!("{other:?}"),
    }
}

/// A value given on the command line as `ros2 param set` reads it (YAML).
fn value_of(text: &str) -> Result<ParameterValue> {
    Ok(match ParamValue::parse(text) {
        ParamValue::Bool(b) => ParameterValue::Boolean(b),
        ParamValue::Integer(i) => ParameterValue::Integer(i),
        ParamValue::Double(d) => ParameterValue::Double(d),
        ParamValue::String(s) => ParameterValue::String(s),
        ParamValue::Array(a) => {
            let all = |f: fn(&ParamValue) -> bool| a.iter().all(f);
            if all(|v| matches!(v, ParamValue::Integer(_))) {
                ParameterValue::IntegerArray(
                    a.iter()
                        .map(|v| match v {
                            ParamValue::Integer(i) => *i,
                            _ => unreachable!("checked"),
                        })
                        .collect(),
                )
            } else {
                ParameterValue::StringArray(a.iter().map(ParamValue::flag_text).collect())
            }
        }
    })
}

/// Runs `iasm ros2-call`.
///
/// # Errors
/// DDS that cannot start, no answer in time, or a set refused (its reason).
pub fn call_node(a: &Ros2CallArgs) -> Result<Outcome> {
    let (_ctx, mut n, _dp) = super::participant(
        a.domain_id,
        "/",
        "iasm_call",
        ros2_client::NodeOptions::new()
            .start_parameter_services(false)
            .enable_rosout(false),
    )?;
    let timeout = Duration::from_secs_f64(a.timeout);
    let node = a.node.as_str();
    let rcl = |ty| ("rcl_interfaces", ty);
    match &a.what {
        Ros2CallWhat::List => {
            let r: ListParametersResponse = call(
                &mut n,
                (node, "list_parameters"),
                rcl("ListParameters"),
                &ListParametersRequest {
                    prefixes: Vec::new(),
                    depth: 0,
                },
                timeout,
            )?;
            for name in r.result.names {
                println!("  {name}");
            }
        }
        Ros2CallWhat::Get { name } => {
            let r: GetParametersResponse = call(
                &mut n,
                (node, "get_parameters"),
                rcl("GetParameters"),
                &GetParametersRequest {
                    names: vec![name.clone()],
                },
                timeout,
            )?;
            let v = r
                .values
                .into_iter()
                .next()
                .map(ParameterValue::from)
                .ok_or_else(|| anyhow!("{node}: no value for {name}"))?;
            println!("{name}: {}", shown(&v));
        }
        Ros2CallWhat::Set { name, value } => {
            let r: SetParametersResponse = call(
                &mut n,
                (node, "set_parameters"),
                rcl("SetParameters"),
                &SetParametersRequest {
                    parameter: vec![
                        Parameter {
                            name: name.clone(),
                            value: value_of(value)?,
                        }
                        .into(),
                    ],
                },
                timeout,
            )?;
            match r.results.first() {
                Some(r) if r.successful => println!("set {name} to {value}"),
                Some(r) => bail!("{node} refused {name} = {value}: {}", r.reason),
                None => bail!("{node}: no result for {name}"),
            }
        }
        Ros2CallWhat::SaveMap | Ros2CallWhat::GetMap | Ros2CallWhat::ClearMap => {
            let name = match a.what {
                Ros2CallWhat::SaveMap => "save_map",
                Ros2CallWhat::GetMap => "get_map",
                _ => "clear_map",
            };
            let r: TriggerResponse = call(
                &mut n,
                (node, name),
                ("std_srvs", "Trigger"),
                &TriggerRequest {
                    structure_needs_at_least_one_member: 0,
                },
                timeout,
            )?;
            if !r.success {
                bail!("{node}/{name}: {}", r.message);
            }
            println!("{}", r.message);
        }
    }
    Ok(Outcome::Success)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_typed_as_ros2_param_set_types_them() {
        assert_eq!(
            value_of("mvdr").unwrap(),
            ParameterValue::String("mvdr".into())
        );
        assert_eq!(value_of("8").unwrap(), ParameterValue::Integer(8));
        assert_eq!(value_of("0.5").unwrap(), ParameterValue::Double(0.5));
        assert_eq!(value_of("false").unwrap(), ParameterValue::Boolean(false));
        assert_eq!(
            value_of("[1, 2]").unwrap(),
            ParameterValue::IntegerArray(vec![1, 2])
        );
    }
}
