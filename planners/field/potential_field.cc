// Placeholder (issue 4).
