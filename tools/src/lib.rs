/// `.utl` listings and hex images (the `utile` tool, issue 6).
pub mod listing;
/// `utile sim`: timelines, simulation on the core engine, VCD (issue 6).
pub mod simulate;
/// SVG timing diagrams (issue 6).
pub mod diagram;
/// The virtual Nano (`cargo nano`): firmware in simavr, UART on a terminal or pty.
pub mod vnano;
/// Benchmarks of the real firmware image in simavr (`bench` binary, issue 7).
pub mod bench;
