// Implemented by its helper; see the header.
