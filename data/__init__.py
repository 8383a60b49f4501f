"""The repository's real-robot recordings and their converters (not installed with the
package): ``from data import real_robots`` from the repository root."""
