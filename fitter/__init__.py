"""Body model, cost, optimisers, measurements, reports and the `fitter` CLI."""
