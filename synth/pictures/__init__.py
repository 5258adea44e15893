"""Pictures of a plan and its proof: matplotlib figures from records, and the 3-D view."""
