//! The `iasm` binary: parses the command line and reports the outcome as an exit status
//! (0 success, 1 a threshold failed, 2 an error).

fn main() -> std::process::ExitCode {
    iasm::main()
}
