//! The `experiment` command: runs the command line, prints an error with its chain of sources
//! (each source's text once: the harness's errors already print theirs) and exits non-zero.

fn main() {
    let code = visfield::experiment::cli::main().unwrap_or_else(|e| {
        eprintln!("error: {}", e.chain());
        1
    });
    std::process::exit(code);
}
