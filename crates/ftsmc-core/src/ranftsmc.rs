//! RANFTSMC (placeholder, being written).
