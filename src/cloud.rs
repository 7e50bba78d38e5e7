//! PLY point-cloud loading.
