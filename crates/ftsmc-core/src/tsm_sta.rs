//! TSM-STA (placeholder, being written).
