//! The commands that live outside main.rs.

pub mod corpus;
