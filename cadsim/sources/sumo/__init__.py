"""The SUMO traffic source (libsumo): network build, command line, frames, static scene. Imports no other source."""
