"""The measures of the dynamic-mesh literature, functions of sequences: distortion (the KG error
with the Karni-Gotsman denominator, the largest vertex distance, :mod:`.distortion`), the
perception-correlated STED (:mod:`.perceptual`) and the rate in bpfv (:mod:`.rate`)."""
