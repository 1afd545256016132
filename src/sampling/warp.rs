//! Square ↔ disk ↔ hemisphere warps, each with its inverse and density.
