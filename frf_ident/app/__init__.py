"""
Application functions used by both the CLI and the nodes.

identify, estimate (in memory or streamed), import, diagnose, reproduce, demo, and the node-graph
driver.
"""
