# GPU particle benchmark (owned by the gpu module): particles per ms per pass, 16k…1M.
