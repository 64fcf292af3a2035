"""What a run means: trace metrics (cards, stick-slip, stresses, Goodman), the per-stroke summary and its compiled
pass, pump-card reading, controller features, downhole-card diagnosis, fitting a model to a measured card, and
drawing cards."""
