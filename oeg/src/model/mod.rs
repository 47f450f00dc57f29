//! The OEG update rules and the options that parameterise them.
//!
//! * [`equations`]: the paper's equations (sections 3 and 4), one pure function each;
//! * [`rules`]: the rules beyond the paper (free space in 2.5D, surface fusion, honest variance), one pure
//!   function each;
//! * [`options`]: the options that choose and parameterise them, with their documented defaults;
//! * [`preset`]: named sets of options (`paper`, `robust`).
//!
//! [`crate::integrate`] strings them together as the paper's Algorithm 1 does.

pub mod equations;
pub mod options;
pub mod preset;
pub mod rules;

pub use equations::*;
pub use options::*;
pub use preset::MapPreset;
pub use rules::*;
