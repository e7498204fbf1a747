"""qrtplan-view: qrtpland's plans, status, joint states and scans as a live
Foxglove view (WebSocket) and an MCAP recording (docs/view.md)."""
