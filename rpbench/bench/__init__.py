"""The solver benchmark: the runner that times presets on models (:mod:`.runner`),
snapshot instances taken from simulations (:mod:`.snapshot`), synthetic model
families (:mod:`.synthetic`) and the committed example instances (:mod:`.examples`)."""
