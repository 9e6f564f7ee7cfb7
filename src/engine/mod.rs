//! Above the stages: what runs them beyond the local pipeline run.
pub mod distributed;
