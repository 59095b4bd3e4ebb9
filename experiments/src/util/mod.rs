//! Leaves every stage may use: atomic file writes ([`output`]), the
//! process's CPU time ([`cpu`]) and memory ([`memory`]), a stop asked for
//! from outside ([`stop`]), and a sweep's shards ([`shard`]).

pub mod cpu;
pub mod memory;
pub mod output;
pub mod shard;
pub mod stop;
