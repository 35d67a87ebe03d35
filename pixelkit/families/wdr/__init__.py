"""The wide-dynamic-range pixel with self-adjusting exposure [Zhou2017]:
an integration capacitor, an in-pixel comparator against V0 and time-to-voltage coding."""
