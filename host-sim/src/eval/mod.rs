//! Evaluation of a walk: the multi-body ZMP of the planned motion ([`multibody`]), the paper's
//! modification experiments ([`paper`]) and the fault sweep over the bus ([`faults`]).
pub mod faults;
pub mod multibody;
pub mod paper;
