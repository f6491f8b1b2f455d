//! Rendering of analysis results as tables, JSON and Graphviz DOT. Works from the serializable library types only.
