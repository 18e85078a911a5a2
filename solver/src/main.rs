fn main() -> std::process::ExitCode {
    solver::cli::main()
}
