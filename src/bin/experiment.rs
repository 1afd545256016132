fn main() {
    visfield::experiment::cli::main();
}
