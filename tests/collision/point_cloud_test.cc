// Placeholder: tests land with issue 4.
