"""Point clouds: downsampling, clustering, ground planes."""
