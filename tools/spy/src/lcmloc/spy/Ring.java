package lcmloc.spy;

import java.util.ArrayList;
import java.util.List;

/** A bounded FIFO: adding to a full ring drops its oldest element. Not thread-safe. */
public final class Ring<T> {
    private final Object[] items;
    private int start;
    private int size;
    private long added;

    public Ring(int capacity) {
        if (capacity < 1) {
            throw new IllegalArgumentException("ring capacity must be at least 1, got " + capacity);
        }
        items = new Object[capacity];
    }

    public void add(T item) {
        items[(start + size) % items.length] = item;
        if (size < items.length) {
            ++size;
        } else {
            start = (start + 1) % items.length;
        }
        ++added;
    }

    public int size() { return size; }

    public int capacity() { return items.length; }

    /** Elements added since construction, dropped ones included. */
    public long added() { return added; }

    /** The i-th oldest element held. */
    @SuppressWarnings("unchecked")
    public T get(int i) {
        if (i < 0 || i >= size) {
            throw new IndexOutOfBoundsException("ring index " + i + " of " + size);
        }
        return (T) items[(start + i) % items.length];
    }

    /** The newest element, or null when empty. */
    public T last() { return size == 0 ? null : get(size - 1); }

    /** A copy of the elements, oldest first. */
    public List<T> toList() {
        List<T> out = new ArrayList<>(size);
        for (int i = 0; i < size; ++i) {
            out.add(get(i));
        }
        return out;
    }
}
