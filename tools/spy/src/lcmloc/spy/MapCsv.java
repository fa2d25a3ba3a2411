package lcmloc.spy;

import java.io.BufferedReader;
import java.io.IOException;
import java.io.Reader;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.Collections;
import java.util.HashSet;
import java.util.List;
import java.util.Set;

/**
 * A map CSV of lcmloc (fusion.map_file: markers, landmarks or beacons): one element per line as
 * id,x,y in metres, an optional header line "id,x,y", blank lines and lines starting with # ignored.
 * A bad line is an error naming the file and the line.
 */
public final class MapCsv {
    /** One map element. */
    public static final class Element {
        public final int id;
        public final double x;
        public final double y;

        public Element(int id, double x, double y) {
            this.id = id;
            this.x = x;
            this.y = y;
        }
    }

    private MapCsv() {}

    /** Reads the map file; IllegalArgumentException "FILE:LINE: what" on a bad line. */
    public static List<Element> read(Path file) throws IOException {
        try (BufferedReader in = Files.newBufferedReader(file, StandardCharsets.UTF_8)) {
            return parse(in, file.toString());
        }
    }

    /** Parses a map from in; name prefixes the error messages. */
    public static List<Element> parse(Reader in, String name) throws IOException {
        BufferedReader lines = in instanceof BufferedReader ? (BufferedReader) in : new BufferedReader(in);
        List<Element> out = new ArrayList<>();
        Set<Integer> ids = new HashSet<>();
        String line;
        int number = 0;
        while ((line = lines.readLine()) != null) {
            ++number;
            String text = line.trim();
            if (text.isEmpty() || text.startsWith("#")) {
                continue;
            }
            String[] f = text.split(",", -1);
            if (number == 1 && f.length >= 1 && f[0].trim().equalsIgnoreCase("id")) {
                continue;
            }
            if (f.length != 3) {
                throw error(name, number, "expected 3 fields id,x,y, got " + f.length + ": '" + text + "'");
            }
            int id;
            try {
                id = Integer.parseInt(f[0].trim());
            } catch (NumberFormatException e) {
                throw error(name, number, "id is not an integer: '" + f[0].trim() + "'");
            }
            double x = number(f[1], "x", name, number);
            double y = number(f[2], "y", name, number);
            if (!ids.add(id)) {
                throw error(name, number, "duplicate id " + id);
            }
            out.add(new Element(id, x, y));
        }
        return Collections.unmodifiableList(out);
    }

    private static double number(String field, String what, String name, int line) {
        double v;
        try {
            v = Double.parseDouble(field.trim());
        } catch (NumberFormatException e) {
            throw error(name, line, what + " is not a number: '" + field.trim() + "'");
        }
        if (!Double.isFinite(v)) {
            throw error(name, line, what + " is not finite: '" + field.trim() + "'");
        }
        return v;
    }

    private static IllegalArgumentException error(String name, int line, String what) {
        return new IllegalArgumentException(name + ":" + line + ": " + what);
    }
}
